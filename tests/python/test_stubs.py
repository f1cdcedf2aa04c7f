"""The stubs (__init__.pyi) name every public binding, and every binding has a docstring help() shows."""
import ast
import os

import yawdepth


def stub_names():
    path = os.path.join(os.path.dirname(yawdepth.__file__), "__init__.pyi")
    tree = ast.parse(open(path).read())
    return {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}


def test_every_binding_has_a_stub_and_a_docstring():
    public = {n for n in yawdepth.__all__}
    missing = public - stub_names()
    assert not missing, f"not in __init__.pyi: {sorted(missing)}"
    undocumented = [n for n in public if not (getattr(yawdepth, n).__doc__ or "").strip()]
    assert not undocumented, undocumented
