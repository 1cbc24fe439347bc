"""The house stays as it is built: src/warprt imports downstream only (scene -> geometry -> kernels ->
image -> dataset -> cli), with no import circle, and tests, benchmarks and reference/ use the package's faces."""

import ast
import functools
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "src" / "warprt"
LAYERS = ("scene", "geometry", "kernels", "image", "dataset")  # the data flow, upstream first
# warprt.options is a face too: the options schema the CLI and the Python API are both built from; and
# warprt.torch, the frames as PyTorch tensors (imported only by who asks for it).
FACES = {"warprt", "warprt.cli", "warprt.options", "warprt.torch", *(f"warprt.{layer}" for layer in LAYERS)}


def module_files(package: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every .py under ``package`` (a folder named as the package)."""
    out = {}
    for p in package.rglob("*.py"):
        rel = p.relative_to(package.parent).with_suffix("")
        out[".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts)] = p
    return out


def imports_of(name: str, path: Path, modules: dict) -> set[str]:
    """The package's modules that ``name`` imports, function-local imports included; an import of a
    package's own __init__ from inside that package (``from . import x``) names the module x."""
    is_package = path.name == "__init__.py"
    here = name if is_package else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = here.split(".")[: len(here.split(".")) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in modules:
                t = t.rsplit(".", 1)[0] if "." in t else ""
            if t and t != name and not (modules[t].name == "__init__.py" and name.startswith(t + ".")):
                found.add(t)
    return found


@functools.cache  # one parse of the package for every test that reads its graph
def import_graph(package: Path) -> dict[str, set[str]]:
    modules = module_files(package)
    return {m: imports_of(m, p, modules) for m, p in modules.items()}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every strongly connected set of two or more modules (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_src_has_no_import_circle():
    assert circles(import_graph(PACKAGE)) == []


def package_copy(tmp_path) -> Path:
    """A copy of the package's modules under tmp_path/warprt, for a negative control to plant a fault in."""
    pkg = tmp_path / "warprt"
    for p in PACKAGE.rglob("*.py"):
        dest = pkg / p.relative_to(PACKAGE)
        dest.parent.mkdir(parents=True, exist_ok=True)
        dest.write_text(p.read_text())
    return pkg


def test_a_planted_circle_is_found(tmp_path):
    """The negative control: the same check on a copy of the package with one import turned back up."""
    pkg = package_copy(tmp_path)
    model = pkg / "scene" / "model.py"
    model.write_text(model.read_text() + "\n\ndef _planted():\n    from ..image import renderer\n")
    found = circles(import_graph(pkg))
    assert found and any("warprt.scene.model" in c and "warprt.image.renderer" in c for c in found)


@pytest.mark.parametrize("layer", LAYERS)
def test_each_layer_imports_only_upstream(layer):
    below = LAYERS[LAYERS.index(layer) + 1:]
    graph = import_graph(PACKAGE)
    wrong = {(m, t) for m, ts in graph.items() if m.startswith(f"warprt.{layer}.") or m == f"warprt.{layer}"
             for t in ts if any(t == f"warprt.{b}" or t.startswith(f"warprt.{b}.") for b in below + ("cli",))}
    assert not wrong


def test_the_scene_layer_needs_no_warp():
    for p in (PACKAGE / "scene").rglob("*.py"):
        names = {a.name.split(".")[0] for n in ast.walk(ast.parse(p.read_text())) if isinstance(n, ast.Import) for a in n.names}
        names |= {(n.module or "").split(".")[0] for n in ast.walk(ast.parse(p.read_text())) if isinstance(n, ast.ImportFrom) and not n.level}
        assert "warp" not in names, p


def test_tests_benchmarks_and_reference_use_the_package_faces():
    outside = []
    for folder in ("tests", "benchmarks", "reference"):
        for p in (ROOT / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(p.read_text())):
                names = [node.module] if isinstance(node, ast.ImportFrom) and not node.level else \
                        [a.name for a in node.names] if isinstance(node, ast.Import) else []
                names += [a.args[0].value for a in [node] if isinstance(node, ast.Call) and getattr(node.func, "attr", "")
                          == "import_module" and node.args and isinstance(node.args[0], ast.Constant)]
                outside += [(str(p.relative_to(ROOT)), n) for n in names if n and n.split(".")[0] == "warprt" and n not in FACES]
    assert outside == []


FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")  # a long option: --shadow-rays, --aov; not '----' rules


def flags_mentioned(package: Path) -> list[tuple[str, int, str]]:
    """(file, line, flag) for each CLI flag in a string literal or docstring of a module of ``package``
    other than its cli.py, the one module that speaks the command line's vocabulary."""
    found = []
    for p in sorted(package.rglob("*.py")):
        if p == package / "cli.py":
            continue
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                found += [(str(p.relative_to(package)), node.lineno, m) for m in FLAG.findall(node.value)]
    return found


def test_only_the_command_line_mentions_its_flags():
    """Below cli.py the library names its Python arguments (render(shadows=...)); cli.py's FLAGS rewords them."""
    assert flags_mentioned(PACKAGE) == []


def test_a_planted_flag_is_found(tmp_path):
    """The negative control: a copy of the package with a flag in one error message and one docstring."""
    pkg = package_copy(tmp_path)
    launch = pkg / "image" / "launch.py"
    launch.write_text(launch.read_text() + '\n\ndef _planted(t):\n    """As --threads says."""\n'
                      '    raise ValueError(f"command line: --threads: got {t}")\n')
    assert [(f, flag) for f, _, flag in flags_mentioned(pkg)] == [("image/launch.py", "--threads")] * 2


def warp_imported_by(statement: str) -> bool:
    """Whether ``statement``, run in a fresh interpreter, leaves Warp in sys.modules."""
    import subprocess
    import sys

    code = f"import sys\n{statement}\nprint('warp' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    return out.stdout.split()[-1] == "True"


@pytest.mark.parametrize("statement", ["import warprt", "import warprt.scene", "import reference",
                                       "import warprt; warprt.load_scene('scenes/cornell.toml')"])
def test_reading_scenes_does_not_import_warp(statement):
    """Cold start: warprt/__init__.py defers render and batch, the one place Warp's import waits."""
    assert not warp_imported_by(statement)


def test_rendering_imports_warp():
    """The negative control: the same check sees Warp once render is asked for."""
    assert warp_imported_by("import warprt; warprt.render")
