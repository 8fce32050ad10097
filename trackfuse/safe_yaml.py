"""Parse untrusted YAML with bounds (``docs/configs.md``, "Limits and one-line errors"):
duplicate keys, recursive aliases, more than :data:`MAX_NODES` nodes once aliases are
expanded ("billion laughs") and files over :data:`MAX_BYTES` are refused with a one-line
:class:`YamlInputError`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from trackfuse.regular_files import open_regular

MAX_BYTES = 1_000_000
MAX_NODES = 100_000
_MERGE_TAG = "tag:yaml.org,2002:merge"


class YamlInputError(ValueError):
    """YAML text that is refused; ``str(err)`` is one line (without the file name)."""


class _StrictLoader(yaml.SafeLoader):
    """A safe loader that refuses a mapping naming one key (or the merge key ``<<``) twice."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[Any] = set()
        merges = 0
        for key_node, _ in node.value:
            if key_node.tag == _MERGE_TAG:
                merges += 1
                if merges > 1:  # the second would silently give its keys a second time
                    raise YamlInputError(f"line {key_node.start_mark.line + 1}: merge key "
                                         "'<<' given twice; allowed: one '<<' with a list "
                                         "of mappings, <<: [*a, *b]")
                continue
            key = self.construct_object(key_node, deep=True)
            try:
                duplicate = key in seen
                seen.add(key)
            except TypeError:  # an unhashable key; the base class reports it
                continue
            if duplicate:
                text = repr(key) if len(repr(key)) <= 60 else repr(key)[:57] + "..."
                raise YamlInputError(f"line {key_node.start_mark.line + 1}: duplicate key "
                                     f"{text}")
        return super().construct_mapping(node, deep=deep)


def expanded_size(root: yaml.Node, limit: int = MAX_NODES) -> int:
    """Number of nodes of ``root`` with every alias expanded (counting stops past ``limit``);
    :class:`YamlInputError` for a recursive alias."""
    sizes: dict[int, int] = {}
    active: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if children_done:
            active.discard(key)
            sizes[key] = min(limit + 1, 1 + sum(sizes[id(c)] for c in _children(node)))
            continue
        if key in sizes:
            continue
        if key in active:
            raise YamlInputError("an alias refers to the value that contains it")
        active.add(key)
        stack.append((node, True))
        stack.extend((c, False) for c in _children(node) if id(c) not in sizes)
    return sizes[id(root)]


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


def load_yaml(text: str) -> Any:
    """Parse one YAML document within this module's bounds, or :class:`YamlInputError`."""
    if len(text) > MAX_BYTES:
        raise YamlInputError(f"larger than {MAX_BYTES} bytes")
    try:
        loader = _StrictLoader(text)
    except yaml.YAMLError as err:  # the reader refuses control characters at once
        raise YamlInputError(f"invalid YAML: {getattr(err, 'reason', None) or 'bad text'}") \
            from None
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        if expanded_size(node) > MAX_NODES:
            raise YamlInputError(f"aliases expand to more than {MAX_NODES} values")
        return loader.construct_document(node)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        problem = getattr(err, "problem", None) or "invalid YAML"
        raise YamlInputError(f"invalid YAML: {where}{problem}") from None
    except (ValueError, TypeError, RecursionError, OverflowError) as err:
        if isinstance(err, YamlInputError):
            raise
        raise YamlInputError(f"invalid YAML: {type(err).__name__}") from None
    finally:
        loader.dispose()


def read_yaml_file(path: str | Path, regular_only: bool = False) -> Any:
    """Parse the UTF-8 YAML file at ``path`` within this module's bounds. ``regular_only`` refuses
    anything but a regular file (a file found in a run folder). Raises :class:`YamlInputError`
    (one line, no file name) or ``OSError``."""
    with (open_regular(path) if regular_only else open(path, "rb")) as fh:
        data = fh.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise YamlInputError(f"larger than {MAX_BYTES} bytes; a config is a short text file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise YamlInputError("not UTF-8 text") from None
    return load_yaml(text)
