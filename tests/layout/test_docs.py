"""The README stays a front page and its pointers stay true: at most 150 lines, every link to a file
(and heading) that exists, every `warprt ...` line a command the CLI's own parser accepts."""

import ast
import re
import shlex
from pathlib import Path

import pytest

import warprt
from warprt.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
MAX_README_LINES = 150
# The pages the README's reference parts moved to (issue 22); each must exist and be linked from the README.
PAGES = ("scene-format", "files", "glass", "cli", "batch", "architecture", "robustness", "accuracy", "testing")

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)


def markdown_files() -> list[Path]:
    return [README, *sorted(DOCS.glob("*.md"))]


def links(path: Path) -> list[str]:
    """The link targets of a Markdown file, outside its code blocks."""
    return LINK.findall(FENCE.sub("", path.read_text()))


def slug(heading: str) -> str:
    """A heading's anchor as GitHub makes it: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    text = FENCE.sub("", path.read_text())
    return {slug(m) for m in re.findall(r"^#+ (.+)$", text, re.M)}


def code_blocks(path: Path, language: str) -> list[str]:
    return [body for lang, body in FENCE.findall(path.read_text()) if lang == language]


def command_lines(path: Path) -> list[str]:
    """The `warprt ...` lines of a file's sh blocks."""
    return [line.strip() for body in code_blocks(path, "sh") for line in body.splitlines()
            if line.strip().startswith("warprt ") or line.strip() == "warprt"]


def parse(line: str):
    """The line's arguments as the CLI's own parser reads them; a ValueError where it refuses them."""
    words = shlex.split(line, comments=True)
    assert words[0] == "warprt"
    try:
        return build_parser().parse_args(words[1:])
    except SystemExit as e:  # argparse's way to refuse (or to print --help): not a command
        raise ValueError(f"the CLI's parser refuses '{line}' (exit {e.code})") from None


def test_the_readme_is_a_front_page():
    lines = README.read_text().splitlines()
    assert len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines; reference material goes to docs/"


def test_every_page_the_readme_lost_exists_and_is_linked_from_it():
    linked = set(links(README))
    for page in PAGES:
        assert (DOCS / f"{page}.md").is_file(), f"docs/{page}.md is missing"
        assert f"docs/{page}.md" in linked, f"README.md does not link docs/{page}.md"
    for path in DOCS.glob("*.md"):
        assert f"docs/{path.name}" in linked, f"docs/{path.name} is not linked from README.md"


@pytest.mark.parametrize("path", markdown_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_to_a_file_resolves(path):
    broken = []
    for target in links(path):
        if re.match(r"[a-z]+:", target):  # https:, mailto:: not a file of the repository
            continue
        file, _, anchor = target.partition("#")
        dest = (path.parent / file).resolve() if file else path
        if not dest.exists():
            broken.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{target}: no heading '#{anchor}' in {dest.relative_to(ROOT)}")
    assert not broken, f"{path.relative_to(ROOT)}: " + "; ".join(broken)


def test_the_readme_shows_about_eight_commands():
    assert len(command_lines(README)) >= 6


@pytest.mark.parametrize("line", command_lines(README))
def test_each_readme_command_parses_and_names_files_that_exist(line):
    args = parse(line)
    for name in ("scene", "job"):
        given = getattr(args, name, None)
        if given is not None:
            assert (ROOT / given).is_file(), f"'{line}' names {given}, which is not in the repository"


@pytest.mark.parametrize("line", [line for page in sorted(DOCS.glob("*.md")) for line in command_lines(page)])
def test_each_docs_command_parses(line):
    parse(line)


@pytest.mark.parametrize("line", ["warprt render --no-such-flag", "warprt render --shadow-rays nope",
                                  "warprt paint scenes/seed.toml", "warprt batch"])
def test_the_command_check_refuses_what_the_cli_refuses(line):
    with pytest.raises(ValueError):
        parse(line)


def test_the_readme_python_uses_only_the_package_face():
    (block,) = code_blocks(README, "python")
    tree = ast.parse(block)  # a SyntaxError fails the test
    used = {n.attr for n in ast.walk(tree)
            if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name) and n.value.id == "warprt"}
    assert used and used <= set(warprt.__all__), f"not in warprt.__all__: {sorted(used - set(warprt.__all__))}"


def test_the_example_job_file_is_a_valid_job():
    from warprt.dataset import check_scene, load_job

    job = load_job(DOCS / "examples" / "orbit.toml")
    check_scene(job)
    assert len(job.frames) == 8
