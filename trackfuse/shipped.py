"""The paper configs shipped with the package, so they work outside a checkout.

The top-level ``configs/`` folder of the repository installs as the data package
``trackfuse.configs`` (see ``pyproject.toml``). :func:`config_path` lets the command line
accept a shipped config by name (``trackfuse run twin_sensor_orbit``) wherever it is run.
"""

from __future__ import annotations

from pathlib import Path

import trackfuse


def configs_folder() -> Path | None:
    """The shipped configs: ``trackfuse/configs`` of an installed package, else a source
    checkout's ``configs/`` beside the package; ``None`` if neither holds a config."""
    package = Path(trackfuse.__file__).resolve().parent
    for folder in (package / "configs", package.parent / "configs"):
        if folder.is_dir() and any(folder.glob("*.yaml")):
            return folder
    return None


def config_path(given: Path) -> Path:
    """``given`` if it exists, else the shipped config of that name (with or without
    ``.yaml``, ``ci/`` allowed), else ``given`` unchanged (the loader reports it)."""
    if given.exists():
        return given
    folder = configs_folder()
    if folder is None or given.is_absolute():
        return given
    name = given if given.suffix == ".yaml" else given.with_name(f"{given.name}.yaml")
    for candidate in (folder / name, folder / name.name):
        if candidate.is_file():
            return candidate
    return given
