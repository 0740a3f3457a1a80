"""The code that ships runs on the numpy each supported Blender bundles:
every `np.<name>` it names exists in the numpy this test runs under. In the
Blender 4.2 environment that is numpy 1.24.3, the oldest of them, so an API
added in numpy 2 (np.strings, np.unstack, ...) fails here by name."""

import ast
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
# What the extension's zip holds: everything but what blender_manifest.toml leaves out.
SHIPPED = [REPO / "__init__.py"] + [path for folder in ("caustic_addon", "export", "jobs", "operators", "panels",
                                                   "properties", "comparison", "writeback")
                                    for path in sorted((REPO / folder).rglob("*.py"))]


def numpy_names(tree: ast.AST) -> set[str]:
    """Dotted names under `np` in a module, e.g. 'np.linalg.norm'."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            parts = []
            while isinstance(node, ast.Attribute):
                parts.append(node.attr)
                node = node.value
            if isinstance(node, ast.Name) and node.id == "np":
                names.add(".".join(["np"] + parts[::-1]))
    return names


def resolves(dotted: str) -> bool:
    owner = np
    for part in dotted.split(".")[1:]:
        if not hasattr(owner, part):
            return False
        owner = getattr(owner, part)
    return True


def test_the_finder_sees_numpy_names():
    assert numpy_names(ast.parse("import numpy as np\nx = np.linalg.norm(np.strings.find(a, 'b'))")) == {
        "np.linalg.norm", "np.linalg", "np.strings.find", "np.strings"}
    assert not resolves("np.no_such_function")


def test_every_numpy_name_in_the_shipped_code_exists_in_this_numpy():
    missing = sorted(f"{path.relative_to(REPO)}: {name}" for path in SHIPPED
                     for name in numpy_names(ast.parse(path.read_text(), str(path))) if not resolves(name))
    assert not missing, f"numpy {np.__version__} lacks: {missing}"
