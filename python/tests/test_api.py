"""The package's surface: the type stubs match the functions, every option
the stubs name is one the command line takes, and every public function
has a docstring with an example."""

import ast
import inspect
import subprocess
from pathlib import Path

import mint_mesh

STUB = Path(mint_mesh.__file__).with_name("__init__.pyi")

# The command behind each function, and the parameters that are Python's
# own (not command-line options).
COMMAND = {
    "resample": "resample", "decimate": "decimate", "simplify": "simplify", "boolean": "bool", "csg": "csg",
    "check": "check", "distance": "distance", "render": "render", "generate": "gen",
    "resample_file": "resample", "decimate_file": "decimate", "simplify_file": "simplify",
    "boolean_file": "bool", "csg_file": "csg", "check_file": "check", "distance_file": "distance",
    "render_file": "render", "convert": "convert", "gen": "gen", "volume": "volume", "volume_file": "volume",
}
PYTHON_ONLY = {"progress", "colors", "target_faces", "path", "tmp"}
# An array's placement: `volume` turns them into the raw file's layout.
PYTHON_ONLY_OF = {"volume": {"spacing", "origin"}}


def stub_functions():
    tree = ast.parse(STUB.read_text())
    return {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}


def test_stubs_cover_every_public_function_with_its_parameters():
    stubs = stub_functions()
    for name in mint_mesh.__all__:
        obj = getattr(mint_mesh, name)
        if not inspect.isfunction(obj):
            continue
        assert name in stubs, f"{name} has no stub"
        runtime = inspect.signature(obj).parameters
        stub = stubs[name].args
        stub_names = {a.arg for a in stub.args + stub.kwonlyargs}
        for p in runtime.values():
            if p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL):
                continue
            assert p.name in stub_names, f"{name}({p.name}) is missing from the stub"


def test_every_stub_option_is_a_command_line_option(mint_exe):
    stubs = stub_functions()
    helps = {}
    for name, command in COMMAND.items():
        if command not in helps:
            helps[command] = subprocess.run([mint_exe, command, "--help"], capture_output=True, text=True).stdout
        for a in stubs[name].args.kwonlyargs:
            if a.arg in PYTHON_ONLY or a.arg in PYTHON_ONLY_OF.get(name, ()):
                continue
            flag = "--" + a.arg.replace("_", "-")
            assert flag in helps[command], f"{name}({a.arg}=): `mint {command}` has no {flag}"


def test_every_public_function_has_an_example():
    for name in mint_mesh.__all__:
        obj = getattr(mint_mesh, name)
        if inspect.isfunction(obj):
            assert ">>> " in (obj.__doc__ or ""), f"{name} has no example"
        else:
            assert obj.__doc__, f"{name} has no docstring"
