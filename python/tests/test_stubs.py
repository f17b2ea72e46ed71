"""The type stubs (gearbif/__init__.pyi) describe the module as it is: every public name of the
module has a stub and every stub a runtime object; every stubbed function and method has the
runtime's parameters, in order, with the same kinds and defaults; every stubbed property exists."""

import ast
import inspect
import pathlib

import pytest

import gearbif

STUB = pathlib.Path(gearbif.__file__).with_name("__init__.pyi")
TREE = ast.parse(STUB.read_text())
# names the stub defines for typing only (aliases, a shared base of the systems)
TYPING_ONLY = {"Section", "Method", "Convention", "Axis", "StrPath", "System", "_System"}


def stub_defs(body):
    out = {}
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            out[node.name] = node
        elif isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name):
            out[node.targets[0].id] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = node
    return out


DEFS = stub_defs(TREE.body)


def stub_params(fn, method):
    """[(name, kind, default or inspect.Parameter.empty)] of a stubbed function."""
    a = fn.args
    out = []
    positional = a.posonlyargs + a.args
    defaults = [inspect.Parameter.empty] * (len(positional) - len(a.defaults)) + [
        ast.literal_eval(d) for d in a.defaults
    ]
    for arg, d in zip(positional, defaults):
        out.append((arg.arg, "positional", d))
    for arg, d in zip(a.kwonlyargs, a.kw_defaults):
        out.append((arg.arg, "keyword", inspect.Parameter.empty if d is None else ast.literal_eval(d)))
    if method and out and out[0][0] in ("self", "cls"):
        out = out[1:]
    return out


def runtime_params(obj):
    kinds = {
        inspect.Parameter.POSITIONAL_ONLY: "positional",
        inspect.Parameter.POSITIONAL_OR_KEYWORD: "positional",
        inspect.Parameter.KEYWORD_ONLY: "keyword",
    }
    sig = inspect.signature(obj)
    out = [(p.name, kinds[p.kind], p.default) for p in sig.parameters.values() if p.kind in kinds]
    if out and out[0][0] in ("self", "cls"):
        out = out[1:]
    return out


def same(stub, runtime):
    """The parameters agree: names, kinds and defaults (a runtime default the extension's text
    signature shows as `...`, e.g. a negative number, only needs a default in the stub)."""
    if [(n, k) for n, k, _ in stub] != [(n, k) for n, k, _ in runtime]:
        return False
    for (_, _, ds), (_, _, dr) in zip(stub, runtime):
        if dr is Ellipsis:
            if ds is inspect.Parameter.empty:
                return False
        elif ds != dr or type(ds) is not type(dr):
            return False
    return True


def test_every_public_name_has_a_stub_and_every_stub_a_runtime_object():
    public = set(gearbif.__all__)
    stubbed = set(DEFS) - TYPING_ONLY
    assert public - stubbed == set(), "public names without a stub"
    assert stubbed - public == set(), "stubs of names the module does not export"


FUNCTIONS = [n for n, d in DEFS.items() if isinstance(d, ast.FunctionDef)]


@pytest.mark.parametrize("name", FUNCTIONS)
def test_function_signatures_match(name):
    assert same(stub_params(DEFS[name], method=False), runtime_params(getattr(gearbif, name)))


def class_members():
    for cname, node in DEFS.items():
        if not isinstance(node, ast.ClassDef) or cname in TYPING_ONLY:
            continue
        bases = [b.id for b in node.bases if isinstance(b, ast.Name)]
        members = [m for m in node.body if isinstance(m, ast.FunctionDef)]
        if "_System" in bases:
            members += [m for m in DEFS["_System"].body if isinstance(m, ast.FunctionDef)]
        for m in members:
            yield cname, m


@pytest.mark.parametrize("cname,member", list(class_members()), ids=lambda v: getattr(v, "name", v))
def test_class_members_match(cname, member):
    cls = getattr(gearbif, cname)
    decorators = {d.id for d in member.decorator_list if isinstance(d, ast.Name)}
    if member.name.startswith("__") and member.name != "__init__":
        assert hasattr(cls, member.name)
        return
    if "property" in decorators:
        assert isinstance(inspect.getattr_static(cls, member.name), property) or hasattr(cls, member.name), member.name
        return
    if member.name == "__init__":
        if cls.__module__ == "gearbif._results" or issubclass(cls, BaseException):
            return
        runtime = runtime_params(cls)
    else:
        runtime = runtime_params(getattr(cls, member.name))
    assert same(stub_params(member, method="staticmethod" not in decorators), runtime)


@pytest.mark.parametrize(
    "cname", [n for n, d in DEFS.items() if isinstance(d, ast.ClassDef) and n not in TYPING_ONLY]
)
def test_every_public_member_of_a_class_has_a_stub(cname):
    cls = getattr(gearbif, cname)
    node = DEFS[cname]
    stubbed = {m.name for m in node.body if isinstance(m, (ast.FunctionDef,))}
    stubbed |= {m.target.id for m in node.body if isinstance(m, ast.AnnAssign)}
    if any(isinstance(b, ast.Name) and b.id == "_System" for b in node.bases):
        stubbed |= {m.name for m in DEFS["_System"].body if isinstance(m, ast.FunctionDef)}
    own = {n for n in vars(cls) if not n.startswith("_")}
    assert own - stubbed == set()
