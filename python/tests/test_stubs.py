"""The type stubs (`cellseq/__init__.pyi`) describe the module as it is: every public name
exists, every stubbed function and method has the runtime's parameters, every public runtime
name is stubbed, and everything has a docstring."""

import ast
import inspect
import os

import cellseq

STUB = os.path.join(os.path.dirname(cellseq.__file__), "__init__.pyi")


def stub_tree():
    with open(STUB) as fh:
        return ast.parse(fh.read())


def params_of(fn: ast.FunctionDef):
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    if a.vararg:
        names.append("*" + a.vararg.arg)
    if a.kwarg:
        names.append("**" + a.kwarg.arg)
    return [n for n in names if n != "self"]


def runtime_params(obj):
    sig = inspect.signature(obj)
    out = []
    for p in sig.parameters.values():
        if p.name in ("self", "cls", "$self", "$cls"):
            continue
        prefix = {p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "")
        out.append(prefix + p.name)
    return out


def test_py_typed_ships():
    assert os.path.exists(os.path.join(os.path.dirname(cellseq.__file__), "py.typed"))


def test_stubs_match_the_runtime():
    tree = stub_tree()
    stubbed = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            stubbed.add(node.name)
            obj = getattr(cellseq, node.name)
            assert runtime_params(obj) == params_of(node), node.name
            assert obj.__doc__, node.name
        elif isinstance(node, ast.ClassDef):
            stubbed.add(node.name)
            cls = getattr(cellseq, node.name)
            assert cls.__doc__, node.name
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and not item.name.startswith("__"):
                    member = getattr(cls, item.name)
                    assert member.__doc__, f"{node.name}.{item.name}"
                    is_property = any(
                        isinstance(d, ast.Name) and d.id == "property" for d in item.decorator_list
                    )
                    if not is_property:
                        assert runtime_params(member) == params_of(item), f"{node.name}.{item.name}"
    public = {n for n in cellseq.__all__ if not n.startswith("__")}
    assert public <= stubbed, public - stubbed
