"""A fork-server preload module that takes a second to load, as a compiling kernel would."""

import time

time.sleep(1.0)
