"""``docs/architecture.md`` names only files and code that exist, and every link into it lands.

The page walks a newcomer through the code file by file, so a renamed module or function that the
page still names sends them looking for something that is not there. These tests read the page's
inline code spans: each path must be a file or folder of the repository, and each name written as
code (``KernelLoop``, ``Intake.submit``, ``render_event()``) must be defined in the sources. Links
from the README and the other pages to ``architecture.md#anchor`` must hit one of its headings.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOC = REPO / "docs" / "architecture.md"
CORE = REPO / "rosaos-core" / "src" / "rosaos"
MAX_LINES = 900
"""Issue 26 asked for a page shorter than its 977 lines; it was cut to about 700, and other pages
hold the figures (``benchmarks/README.md``) and the how-to (``user-guide.md``)."""

CODE_SPAN = re.compile(r"`([^`\n]+)`")
PATH = re.compile(r"^[\w.-]+(/[\w.-]+)*(\.py|\.js|\.md|\.yaml|\.toml|/)$")
NAME = re.compile(r"^(?P<owner>[A-Za-z_]\w*\.)?(?P<name>[A-Za-z_]\w*)(\(.*\))?$")
DEFINED = r"(^|\n)[ \t]*(async[ \t]+def|def|class)[ \t]+{0}\b|(^|\n)[ \t]*{0}[ \t]*[:=]"
SEARCH_ROOTS = [REPO / "rosaos-core" / "src", *sorted((REPO / "plugins").glob("*/src"))]
PATH_ROOTS = [CORE, REPO, *sorted((REPO / "plugins").glob("*/src/*")), REPO / "docs"]
NOT_FILES = ("<", "*", "run/", "logs/", "../shared/", "rosaos.toml")
"""Paths in the data directory, the user's configuration or outside the repository."""
ELSEWHERE = {
    *("Model", "ModelRequest", "FunctionModel", "TestModel", "OpenAIChatModel", "None"),
    *("gc", "freeze", "secrets", "token_urlsafe", "os", "setsid", "O_EXCL", "SCM_RIGHTS", "SOCK_SEQPACKET"),
    "ROSAOS_DRIVERS",
}
"""Names the page takes from Python, the OS and pydantic-ai, and an environment variable."""


def code_spans() -> list[str]:
    return CODE_SPAN.findall(DOC.read_text(encoding="utf-8"))


@cache
def sources() -> str:
    return "\n".join(
        path.read_text(encoding="utf-8") for root in SEARCH_ROOTS for path in sorted(root.rglob("*.py"))
    )


@cache
def defined_names() -> frozenset[str]:
    """Every name the sources define as :data:`DEFINED` says (a ``def``, a ``class``, or an
    assignment or annotation at the start of a line), read in one pass: a search of the whole
    source for each of the page's names took seconds."""
    definition = re.compile(
        r"^[ \t]*(?:(?:async[ \t]+def|def|class)[ \t]+(\w+)|(\w+)[ \t]*[:=])", re.MULTILINE
    )
    return frozenset(found for match in definition.finditer(sources()) for found in match.groups() if found)


def is_defined(name: str) -> bool:
    return name in defined_names()


def path_exists(text: str) -> bool:
    return any((root / text).exists() for root in PATH_ROOTS)


def code_names() -> set[str]:
    """Names the page writes as code: a class (``CamelCase``), a constant (``MAX_DELIVERIES``), a
    call (``name()``) or a ``Owner.member``. Bare lower-case words are left out: they are as often a config key, an event
    kind or a status as a function."""
    found: set[str] = set()
    for span in code_spans():
        match = NAME.match(span)
        if match is None or PATH.match(span):
            continue
        name, owner = match["name"], match["owner"]
        called = span.endswith(")")
        if owner is not None:
            found.add(owner.rstrip("."))
            found.add(name)
        elif called or (name[0].isupper() and "_" not in name) or (name.isupper() and len(name) > 3):
            found.add(name)
    return found - ELSEWHERE


def named_in_file() -> list[tuple[str, str]]:
    """``(path, name)`` for each module the page names with a name right after it, as in
    ```kernel/intake.py` `Intake.submit```: the name must be defined in that very file."""
    pairs = re.findall(r"`([\w/.-]+\.py)` `([A-Za-z_][\w.]*)(?:\(\))?`", DOC.read_text(encoding="utf-8"))
    return [(path, name.split(".")[0]) for path, name in pairs]


def test_a_name_given_beside_a_module_is_defined_in_it() -> None:
    pairs = named_in_file()
    assert len(pairs) > 40, "the scan found too few module-and-name pairs"
    misplaced = []
    for path, name in pairs:
        file = next((root / path for root in PATH_ROOTS if (root / path).is_file()), None)
        text = file.read_text(encoding="utf-8") if file is not None else ""
        if re.search(DEFINED.format(re.escape(name)), text) is None:
            misplaced.append(f"{name} in {path}")
    assert not misplaced, (
        f"docs/architecture.md puts these names in files that do not define them: {misplaced}"
    )


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors() -> set[str]:
    lines = DOC.read_text(encoding="utf-8").splitlines()
    return {slug(line.lstrip("#")) for line in lines if re.match(r"#{1,6} ", line)}


def test_the_page_is_short_enough_to_read() -> None:
    lines = len(DOC.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"docs/architecture.md has {lines} lines; cut repetition below {MAX_LINES}"


def test_the_scan_finds_the_page_paths_and_names() -> None:
    paths = [span for span in code_spans() if PATH.match(span)]
    assert len(paths) > 80 and len(code_names()) > 80
    assert is_defined("Intake") and is_defined("render_event")
    assert not is_defined("NoSuchKernelPart") and not path_exists("kernel/no_such_module.py")


def test_every_path_the_page_names_exists() -> None:
    missing = sorted(
        {
            span
            for span in code_spans()
            if PATH.match(span) and not span.startswith(NOT_FILES) and not path_exists(span)
        }
    )
    assert not missing, (
        f"docs/architecture.md names files that do not exist (paths are under rosaos-core/src/rosaos/ or the repository): {missing}"
    )


def test_every_class_and_function_the_page_names_is_defined() -> None:
    missing = sorted(name for name in code_names() if not is_defined(name))
    assert not missing, (
        f"docs/architecture.md names code that is defined nowhere in rosaos-core or the plugins: {missing}"
    )


def test_the_anchor_slug_follows_github() -> None:
    assert slug("Where the code differs from ARCHITECTURE.md") == "where-the-code-differs-from-architecturemd"
    assert slug("Auth and the HTTP API") == "auth-and-the-http-api"


def test_links_into_the_page_land_on_a_heading() -> None:
    link = re.compile(r"\((?:docs/)?architecture\.md#([\w-]+)\)|\]\(#([\w-]+)\)")
    pages = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
    targets = {
        (page.name, first or second)
        for page in pages
        for first, second in link.findall(page.read_text(encoding="utf-8"))
        if first or page == DOC
    }
    assert targets, "the scan found no links into docs/architecture.md"
    broken = sorted((page, anchor) for page, anchor in targets if anchor not in anchors())
    assert not broken, f"links to headings docs/architecture.md does not have: {broken}"
