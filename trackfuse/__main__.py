"""``python -m trackfuse``: the ``trackfuse`` command line."""

from trackfuse_cli.main import app

if __name__ == "__main__":
    app()
