"""trackfuse: Monte Carlo experiment runner for passive multi-sensor tracking studies."""

__version__ = "0.1.0"
