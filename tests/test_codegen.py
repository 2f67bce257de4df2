"""generated/ is up to date, reproducible and compiles alone under strict flags."""

from __future__ import annotations

import re
import subprocess

import casadi as ca
import pytest

from quadland import codegen
from quadland.build import find_compiler
from quadland.cli import main as cli_main
from quadland.exceptions import CompilerNotFoundError
from symbolic.codegen import CodegenConfig


@pytest.fixture(scope="module")
def files():
    return codegen.generated_files()


def test_generated_is_up_to_date(files):
    text = codegen.diff(codegen.GENERATED_DIR, files)
    assert not text, ("generated/ is out of date with symbolic/: run `quadland codegen`\n"
                      + text[:4000])


def test_regeneration_is_byte_for_byte(files):
    assert codegen.generated_files() == files


def test_check_reports_a_unified_diff(tmp_path, capsys, files):
    codegen.write(tmp_path, files)
    assert cli_main(["codegen", "--out", str(tmp_path), "--check"]) == 0
    (tmp_path / "quadland.h").write_text(files["quadland.h"].replace("QL_OK = 0", "QL_OK = 7"))
    (tmp_path / "plant.c").unlink()
    assert cli_main(["codegen", "--out", str(tmp_path), "--check"]) == 1
    out = capsys.readouterr()
    assert "--- a/quadland.h" in out.out and "-    QL_OK = 7," in out.out
    assert "+++ b/plant.c" in out.out
    assert "quadland codegen --out" in out.err
    assert cli_main(["codegen", "--out", str(tmp_path)]) == 0
    assert codegen.diff(tmp_path, files) == ""


def test_headers_name_builder_version_and_do_not_edit(files):
    for name, text in files.items():
        if name.endswith((".c", ".h")):
            head = text[:600]
            assert f"CasADi {ca.__version__}" in head and "Do not edit" in head, name
            assert "quadland codegen" in head, name
        if name.endswith("Makefile"):
            assert "Do not edit" in text[:600]


def test_no_paths_or_timestamps(files):
    for name, text in files.items():
        assert "/work/" not in text and "/home/" not in text and "/tmp" not in text, name
        assert not re.search(r"20\d\d-\d\d-\d\d", text), name


def test_float_build_has_no_double_constants_or_math(files):
    literal = re.compile(r"(?<![\w.])\d+\.\d*(?:[eE][+-]?\d+)?(?![\w.])(?!f)")
    call = re.compile(r"\b(exp|expm1|cos|sin|tan|tanh|fmin|fmax|fabs|sqrt)\(")
    for name, text in files.items():
        if name.startswith("float/") and name.endswith(".c"):
            body = text.partition("#include <math.h>")[2]
            body = re.sub(r"/\*.*?\*/|\"[^\"\n]*\"", "", body, flags=re.S)
            assert not call.findall(body), name
            bad = [m for m in literal.findall(body) if not m.endswith("f")]
            assert not bad, (name, bad[:5])
    assert "typedef float ql_real;" in files["float/quadland.h"]
    assert "typedef double ql_real;" in files["quadland.h"]


def test_config_literals():
    assert CodegenConfig("float").literal(2) == "2.0f"
    assert CodegenConfig().literal(0.05) == "0.05"
    assert CodegenConfig("float").math("tanh") == "tanhf"
    with pytest.raises(ValueError):
        CodegenConfig("half")


def _compiler():
    try:
        return find_compiler()
    except CompilerNotFoundError:
        pytest.skip("no C compiler")


@pytest.mark.parametrize("folder", ["", "float/"])
def test_every_file_compiles_alone(folder):
    cc = _compiler()
    root = codegen.GENERATED_DIR / folder
    extra = ["-Wdouble-promotion", "-Wfloat-conversion"] if folder else []
    for src in sorted(root.glob("*.c")):
        proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror",
                               *extra, "-fsyntax-only", "-I", str(root), str(src)],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr


def test_no_heap_and_no_casadi_runtime():
    for src in codegen.GENERATED_DIR.rglob("*.[ch]"):
        text = src.read_text()
        assert not re.search(r"\b(malloc|calloc|realloc|free)\s*\(", text), src
        includes = set(re.findall(r"#include [<\"]([^>\"]+)[>\"]", text))
        assert includes <= {"math.h", "stddef.h", "string.h", "stdio.h", "stdlib.h", "time.h",
                            "quadland.h", "control_step.h", "closed_loop.h", "plant.h",
                            "closed_loop_jacobian.h", "paper_scenario.h"}, (src, includes)
