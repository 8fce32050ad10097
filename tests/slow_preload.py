"""A fork-server preload module that loads slowly, as a compiling kernel would: it sleeps for
``TRACKFUSE_TEST_PRELOAD_S`` seconds (default 1)."""

import os
import time

time.sleep(float(os.environ.get("TRACKFUSE_TEST_PRELOAD_S", "1")))
