"""The type stubs describe what the extension exports: every public name, and every parameter of
every function and method, under the same names."""

import ast
import inspect
import pathlib

import meshletlab
from meshletlab import _meshletlab

STUB = pathlib.Path(meshletlab.__file__).with_name("_meshletlab.pyi")


def stub_defs():
    tree = ast.parse(STUB.read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = node
        elif isinstance(node, ast.ClassDef):
            out[node.name] = node
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    out[f"{node.name}.{item.name}"] = item
        elif isinstance(node, ast.AnnAssign):
            out[node.target.id] = node
    return out


def params(fn):
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    return [n for n in names if n != "self"]


def test_every_export_has_a_stub_and_no_stub_is_stale():
    defs = stub_defs()
    public = {n for n in dir(_meshletlab) if not n.startswith("_")}
    top = {n for n in defs if "." not in n and not n.startswith("_")}
    assert public == top
    for name in sorted(public):
        obj = getattr(_meshletlab, name)
        if isinstance(obj, type):
            members = {m for m in vars(obj) if not m.startswith("_")}
            stubbed = {n.split(".", 1)[1] for n in defs if n.startswith(name + ".") and not n.split(".")[1].startswith("_")}
            assert members == stubbed, name


def test_function_parameters_match():
    defs = stub_defs()
    for name, node in defs.items():
        if "." in name or not isinstance(node, ast.FunctionDef):
            continue
        sig = inspect.signature(getattr(_meshletlab, name))
        real = [p.name for p in sig.parameters.values() if p.kind != p.VAR_KEYWORD]
        stub = params(node)
        if any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values()) and node.args.kwarg is None:
            # build's options are spelled out in the stub; they must be the module's own list.
            assert stub[len(real):] == meshletlab.STRATEGY_OPTIONS, name
            stub = stub[: len(real)]
        assert real == stub, name
