"""Bridges to other tracking libraries (optional extras; nothing here is imported by the runner).

* :mod:`trackfuse.interop.stonesoup`: our simulated angle returns as Stone Soup detections and
  measurement models, Stone Soup track states back as our ``(6,)`` estimates and ``(6, 6)``
  covariances, and Stone Soup randomness drawn from a trial's own generator
  (``pip install 'trackfuse[stonesoup]'``; see ``docs/stonesoup.md``).
"""
