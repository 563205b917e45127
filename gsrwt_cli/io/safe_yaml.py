"""YAML from users, read defensively: bounded nesting and aliases, no duplicate keys.

:func:`load_yaml` gives what ``yaml.safe_load`` gives (the same types, merge keys included)
for every document a sidecar could reasonably be, and refuses, with the line, what could hurt:

- nodes nested deeper than :data:`MAX_DEPTH` (PyYAML composes and constructs recursively);
- aliases that multiply the document ("billion laughs"): the node graph is measured as if
  every alias were expanded, without expanding it (memoised over shared nodes), and may be
  at most :data:`EXPANSION_FACTOR` times the nodes the file writes, or
  :data:`MIN_EXPANDED_NODES`, whichever is larger; an alias inside its own anchor is refused;
- a mapping key given twice (PyYAML silently keeps the last value);
- integers of more than :data:`MAX_INTEGER_DIGITS` characters (Python refuses to convert
  them anyway, with a ``ValueError`` PyYAML lets through), and any other value its
  constructor cannot build (a date like ``2024-13-45``).

Every problem is a :class:`YamlInputError` with a line number (when there is one) and a
short one-line description; values are quoted with :func:`~gsrwt_cli.base.messages.quote`.
"""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.constructor import ConstructorError
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from ..base.messages import one_line, quote

#: Deepest nesting of nodes accepted, counted through aliases (a sidecar needs 3).
MAX_DEPTH = 64
#: Expanded nodes always allowed, however small the file.
MIN_EXPANDED_NODES = 10_000
#: Otherwise aliases may make the expanded document at most this many times the written one.
EXPANSION_FACTOR = 10
#: Longest integer scalar, in characters (Python's own default limit for decimal strings).
MAX_INTEGER_DIGITS = 4300
#: Longest problem description kept from PyYAML.
PROBLEM_LIMIT = 200

_MERGE_TAG = "tag:yaml.org,2002:merge"


class YamlInputError(ValueError):
    """YAML text that is invalid or refused; ``line`` is 1-based, or None when unknown;
    ``key`` the mapping key given twice, when that is the problem."""

    def __init__(self, line: int | None, problem: str, key: str | None = None) -> None:
        self.line, self.problem, self.key = line, problem, key
        super().__init__(f"line {line}: {problem}" if line is not None else problem)


class _BoundedLoader(yaml.SafeLoader):
    """SafeLoader that bounds nesting while composing and reports constructor failures."""

    def __init__(self, text: str) -> None:
        super().__init__(text)
        self._depth = 0

    def compose_node(self, parent: Node | None, index: Any) -> Node:
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise yaml.composer.ComposerError(
                    None, None, f"nested deeper than {MAX_DEPTH} levels",
                    self.peek_event().start_mark,
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_object(self, node: Node, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except (ValueError, OverflowError, TypeError) as error:
            raise ConstructorError(
                None, None, f"cannot read the value: {one_line(str(error), 120)}",
                node.start_mark,
            ) from None

    def construct_yaml_int(self, node: ScalarNode) -> int:
        if len(node.value) > MAX_INTEGER_DIGITS:
            raise ConstructorError(
                None, None,
                f"an integer of {len(node.value)} characters is too long "
                f"(at most {MAX_INTEGER_DIGITS})",
                node.start_mark,
            )
        return super().construct_yaml_int(node)


_BoundedLoader.add_constructor("tag:yaml.org,2002:int", _BoundedLoader.construct_yaml_int)


class _OpenCVLoader(_BoundedLoader):
    """:class:`_BoundedLoader` for OpenCV's FileStorage YAML: nodes of its own tags
    (``!!opencv-matrix``, ``!!opencv-nd-matrix``, ...) read as plain YAML, and numbers as
    OpenCV reads them (``1e-05`` and ``.Nan`` are floats, which YAML 1.1 takes for strings)."""

    def construct_opencv_node(self, tag_suffix: str, node: Node) -> Any:
        if isinstance(node, MappingNode):
            return self.construct_yaml_map(node)
        if isinstance(node, SequenceNode):
            return self.construct_yaml_seq(node)
        return self.construct_scalar(node)


_OpenCVLoader.add_multi_constructor("tag:yaml.org,2002:opencv-",
                                    _OpenCVLoader.construct_opencv_node)
_OpenCVLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^(?:[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+|[-+]?\.(?:Nan|Inf))$"),
    list("-+0123456789."),
)


def load_yaml(text: str, *, opencv: bool = False) -> Any:
    """The one YAML document in ``text``, as ``yaml.safe_load`` builds it, or None if empty;
    ``opencv``: as OpenCV's FileStorage YAML (:class:`_OpenCVLoader`; no ``%YAML:1.0`` line).

    Raises :class:`YamlInputError` for invalid YAML and for what the module docstring lists.
    """
    try:
        return _compose_check_construct(text, _OpenCVLoader if opencv else _BoundedLoader)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        problem = error.problem or error.context or "invalid YAML"
        if error.context and problem.startswith("but "):  # "expected ... but found ..."
            problem = f"{error.context} {problem}"
        elif problem == "second occurrence" and error.context_mark is not None:
            problem = f"{error.context} on line {error.context_mark.line + 1}, again here"
        raise YamlInputError(
            mark.line + 1 if mark is not None else None, one_line(problem, PROBLEM_LIMIT)
        ) from None
    except yaml.reader.ReaderError as error:
        line = text.count("\n", 0, error.position) + 1
        character = chr(error.character) if isinstance(error.character, int) else error.character
        raise YamlInputError(line, f"character {quote(character)} is not allowed in YAML") from None
    except yaml.YAMLError as error:
        raise YamlInputError(None, one_line(str(error), PROBLEM_LIMIT)) from None
    except RecursionError:  # not expected with MAX_DEPTH, but never a traceback
        raise YamlInputError(None, "nested too deeply") from None


def _compose_check_construct(text: str, loader_class: type[_BoundedLoader]) -> Any:
    loader = loader_class(text)  # the reader checks the characters here
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        check_node_graph(node)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def _children(node: Node) -> list[Node]:
    if isinstance(node, SequenceNode):
        return list(node.value)
    if isinstance(node, MappingNode):
        return [part for pair in node.value for part in pair]
    return []


def _line(node: Node) -> int:
    return node.start_mark.line + 1


def check_node_graph(root: Node) -> None:
    """Refuse a composed document whose expansion, depth or keys the module docstring forbids.

    Walks the node graph once, without recursion: shared nodes (aliases) are visited once and
    their expanded size is memoised, so a billion-laughs document costs as much as its text.
    """
    sizes: dict[int, int] = {}  # expanded node count, capped
    depths: dict[int, int] = {}
    finished: list[Node] = []  # post-order: children before parents
    open_nodes: set[int] = set()
    cap = 1 << 62
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if children_done:
            open_nodes.discard(key)
            children = _children(node)
            sizes[key] = min(cap, 1 + sum(sizes[id(child)] for child in children))
            depths[key] = 1 + max((depths[id(child)] for child in children), default=0)
            if depths[key] > MAX_DEPTH:
                raise YamlInputError(
                    _line(node), f"nested deeper than {MAX_DEPTH} levels (through aliases)"
                )
            finished.append(node)
            continue
        if key in sizes:
            continue
        if key in open_nodes:
            raise YamlInputError(_line(node), "an alias refers to a collection that contains it")
        open_nodes.add(key)
        if isinstance(node, MappingNode):
            _check_unique_keys(node)
        stack.append((node, True))
        children = [child for child in _children(node) if id(child) not in sizes]
        stack.extend((child, False) for child in reversed(children))
    limit = max(MIN_EXPANDED_NODES, EXPANSION_FACTOR * len(sizes))
    if sizes[id(root)] > limit:
        first = next(node for node in finished if sizes[id(node)] > limit)
        raise YamlInputError(
            _line(first),
            f"aliases expand the document beyond {limit} values (it writes {len(sizes)}); "
            "refusing it",
        )


def _check_unique_keys(node: MappingNode) -> None:
    """A key written twice in one mapping is an error (merge keys ``<<`` may repeat)."""
    seen: dict[tuple[str, str], int] = {}
    for key, _ in node.value:
        if not isinstance(key, ScalarNode) or key.tag == _MERGE_TAG:
            continue
        identity = (key.tag, key.value)
        if identity in seen:
            raise YamlInputError(
                _line(key), f"key {quote(key.value)} given twice (first on line {seen[identity]})",
                key.value,
            )
        seen[identity] = _line(key)
