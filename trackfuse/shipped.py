"""The paper configs shipped with the package (``configs/`` installs as ``trackfuse.configs``)
and how a config NAME is found (``docs/configs.md``)."""

from __future__ import annotations

import difflib
from pathlib import Path

import trackfuse

#: The working directory's configs, preferred to the shipped ones (as by ``reproduce``).
LOCAL_CONFIGS = Path("configs")


def configs_folder() -> Path | None:
    """The shipped configs: installed ``trackfuse/configs``, else a checkout's ``configs/``."""
    package = Path(trackfuse.__file__).resolve().parent
    for folder in (package / "configs", package.parent / "configs"):
        if folder.is_dir() and any(folder.glob("*.yaml")):
            return folder
    return None


def config_folders() -> list[Path]:
    """Where a config name is looked up, in order: ``./configs``, then the shipped configs."""
    found = [LOCAL_CONFIGS] if LOCAL_CONFIGS.is_dir() else []
    shipped = configs_folder()
    if shipped is not None and not (found and LOCAL_CONFIGS.resolve() == shipped):
        found.append(shipped)
    return found


def config_path(given: Path) -> Path:
    """``given`` if it exists; else the config of that name in ``./configs``, else among the
    shipped ones; else ``given`` unchanged for the loader to report."""
    if given.exists() or given.is_absolute():
        return given
    name = given if given.suffix == ".yaml" else given.with_name(f"{given.name}.yaml")
    folders = config_folders()
    shipped = [f / name.name for f in folders if f != LOCAL_CONFIGS]  # configs/x.yaml, outside
    for candidate in [*(f / name for f in folders), *shipped]:
        if candidate.is_file():
            return candidate
    return given


def config_names() -> list[str]:
    """Every config name :func:`config_path` finds, ``./configs`` first, each once."""
    names = [p.relative_to(folder).with_suffix("").as_posix()
             for folder in config_folders() for p in sorted(folder.rglob("*.yaml"))]
    return list(dict.fromkeys(names))


def close_config_names(given: Path, most: int = 3) -> list[str]:
    """Config names close to ``given``: that file name elsewhere, else the ``most`` most similar."""
    text = given.as_posix().removesuffix(".yaml")
    names = [n for n in config_names() if n != text]
    same = [n for n in names if n.rpartition("/")[2] == text.rpartition("/")[2]]
    return same[:most] or difflib.get_close_matches(text, names, n=most, cutoff=0.6)
