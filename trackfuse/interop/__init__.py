"""Bridges to other tracking libraries (optional extras, never imported by the runner):
:mod:`trackfuse.interop.stonesoup` (``docs/stonesoup.md``)."""
