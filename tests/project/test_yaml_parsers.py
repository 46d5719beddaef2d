"""libyaml reads every file as PyYAML's pure-Python parser does, or leaves it to it.

:func:`~rockfall_design.project.yaml_file.parse_yaml` parses with libyaml
(4.7 times faster on the bundled files) and hands a file to the pure-Python
parser, the reference, wherever the two may differ or libyaml fails. The
property: for any text, the same data and line map, or the same message.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from rockfall_design.project import ProjectError
from rockfall_design.project.yaml_file import parse_yaml

ROOT = Path(__file__).resolve().parents[2]

# Pieces of YAML's syntax, those where the two parsers were found to differ
# included (tabs, byte-order marks, tags, "!" alone, block scalar headers,
# directives, a bare "---", the other line breaks).
_PIECES = list("ab1.e-+:{}[],#&*!|>'\"?%@` \n") + [
    "\t", "\r\n", "\r", "\x85", "\u2028", "\u2029", "\ufeff", "\x00", "\x07", "é", "\U0001f600",
    "<<", "~", "null", "1e3", "0x1f", "!!int", "!!str", "!!map", "---", "...", "&a", "*a",
    "<<: *a", "\n  - ", "\n- ", "a: ", "\n  b: ", "%YAML 1.1\n", "%TAG ! x\n", "!x ", "? ",
    "'a''b'", '"\\x41\\u00e9"', "|-\n  ", ">+\n ", "|#", "1_000", ".inf", "yes", "2024-01-01",
    "\n  ", " #c", "# a > b | c ! d %\n", "key: value\n", "x: [1, 2]\n", "- {a: 1}\n",
]


def _read(text: str, libyaml: bool) -> tuple[str, Any]:
    """What :func:`parse_yaml` makes of ``text``: its data and lines, or its message."""
    try:
        return "read", parse_yaml(text, "f.yaml", libyaml=libyaml)
    except ProjectError as exc:
        return "refused", str(exc)


def _same(text: str) -> None:
    fast, reference = _read(text, True), _read(text, False)
    # repr: NaN equals itself there, and 1 and 1.0 or True differ.
    assert repr(fast) == repr(reference), text


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(_PIECES), min_size=1, max_size=40).map("".join))
def test_any_text_reads_the_same_as_with_the_pure_python_parser(text):
    _same(text)


_SCALARS = st.one_of(
    st.integers(-10**7, 10**7), st.floats(allow_nan=True), st.booleans(), st.none(),
    st.sampled_from(["1e3", "yes", "null", "2024-01-01", "0x1f", "1_000", ".5", "~", "-"]),
    st.text(alphabet="ab Zé:#-?'\"\\\n\r\t\x85\u2028{}[],&*!|>%@`~.09eE+_", max_size=12),
)
_DATA = st.recursive(_SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=4),
    st.dictionaries(st.one_of(st.text(max_size=8), st.integers(0, 9)), inner, max_size=4),
), max_leaves=20)


@settings(max_examples=150, deadline=None)
@given(_DATA, st.sampled_from([None, True, False]), st.sampled_from([20, 80]),
       st.booleans(), st.booleans())
def test_written_data_reads_the_same_as_with_the_pure_python_parser(
        data, flow, width, comments, crlf):
    """Files as an editor or a program writes them: quoted, flow and block styles, comments."""
    text = yaml.safe_dump(data, default_flow_style=flow, width=width, allow_unicode=True)
    if comments:
        text = "# a comment > | ! % \t\n" + text.replace("\n", "  # c\n", 1)
    if crlf:
        text = text.replace("\n", "\r\n")
    _same(text)


@pytest.mark.parametrize("path", sorted((ROOT / "projects").glob("*.yaml")), ids=lambda p: p.name)
def test_the_bundled_files_read_the_same_with_both_parsers(path):
    _same(path.read_text(encoding="utf-8"))


@pytest.mark.parametrize(("text", "message"), [
    ("name: x\nseed: !!int\n", "f.yaml:2: invalid YAML: invalid value: !!int '' (column 7)"),
    ("name: x\nok: !!bool x\n", "f.yaml:2: invalid YAML: invalid value: !!bool 'x' (column 5)"),
])
def test_a_tag_on_a_value_it_cannot_convert_is_one_message(text, message):
    """Found by the property above: an IndexError and a KeyError escaped as tracebacks."""
    with pytest.raises(ProjectError) as info:
        parse_yaml(text, "f.yaml")
    assert str(info.value) == message
