"""generated/ is up to date, reproducible and compiles alone under strict flags;
the registry, the struct layouts, the prefixes and the scenario switch."""

from __future__ import annotations

import ctypes
import re
import subprocess

import casadi as ca
import pytest

from quadland import codegen
from quadland.cli import main as cli_main
from quadland.engine import flightcode
from quadland.engine.build import find_compiler
from quadland.exceptions import CompilerNotFoundError
from quadland.kinds.landing.flight import landing_defaults
from quadland.kinds.paper.flight import paper_defaults
from quadland.kinds.paper.simulate import TRAJECTORY
from quadland.scenario import load_scenario
from quadland_symbolic.codegen import (
    FUNCTIONS,
    CodegenConfig,
    c_sources,
    example_columns,
    generate,
    generate_landing,
    land_columns,
)
from quadland_symbolic.codegen.estimator_api import estimator_api_structs
from quadland_symbolic.codegen.land_detector_api import land_detector_api_structs
from quadland_symbolic.codegen.structs import api_structs, landing_api_structs
from quadland_symbolic.landing.sensed_loop import SENSED_TRAJECTORY
from quadland_symbolic.landing.signals import LANDING_TRAJECTORY

GENERATED_DIR = codegen.generated_dir()


@pytest.fixture(scope="module")
def files():
    return codegen.generated_files()


def test_generated_is_up_to_date(files):
    text = codegen.diff(GENERATED_DIR, files)
    assert not text, ("generated/ is out of date with symbolic/: run `quadland codegen`\n"
                      + text[:4000])


def test_regeneration_is_byte_for_byte(files):
    assert codegen.generated_files() == files


@pytest.mark.slow
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
    assert "typedef float qlf_real;" in files["float/quadland.h"]
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
    root = GENERATED_DIR / folder
    extra = ["-Wdouble-promotion", "-Wfloat-conversion"] if folder else []
    for src in sorted(root.glob("*.c")):
        proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror",
                               *extra, "-fsyntax-only", "-I", str(root), str(src)],
                              capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr


def test_no_heap_and_no_casadi_runtime():
    for src in GENERATED_DIR.rglob("*.[ch]"):
        text = src.read_text()
        assert not re.search(r"\b(malloc|calloc|realloc|free)\s*\(", text), src
        includes = set(re.findall(r"#include [<\"]([^>\"]+)[>\"]", text))
        assert includes <= {"math.h", "stddef.h", "string.h", "stdio.h", "stdlib.h", "time.h",
                            "quadland.h", "quadland_landing.h", "quadland_estimator.h",
                            "quadland_land_detector.h",
                            "scenario.h", "land_scenario.h",
                            "quadland_loop.h",
                            *(f"{f.name}.h" for f in FUNCTIONS)}, (src, includes)


# --- the registry -----------------------------------------------------------

#: Each part's header and the node count generated/ has for it (paper, highway).
PARTS = {"paper": ("quadland.h", 100), "landing": ("quadland_landing.h", 10),
         "estimator": ("quadland_estimator.h", 0),
         "land_detector": ("quadland_land_detector.h", 0)}


def test_one_registry_gives_files_symbols_and_wrappers(files):
    for entry in FUNCTIONS:
        header, l = PARTS[entry.part]
        fn = entry.function(l)
        assert fn.name() == entry.name
        for folder, prefix in (("", "ql_"), ("float/", "qlf_")):
            assert f"int {prefix}casadi_{entry.name}(" in files[f"{folder}{entry.name}.h"]
            assert entry.origin(l) in files[f"{folder}{entry.name}.c"][:800]
        if entry.wrapper is None:
            continue
        ins, outs = entry.arguments(l)
        assert (ins, outs) == (tuple(fn.name_in()), tuple(fn.name_out()))
        args = ", ".join([f"const ql_real \\*{a}" for a in ins]
                         + [f"ql_real \\*{r}" for r in outs])
        proto = re.sub(r"\s+", " ", files[header])
        assert re.search(rf"void ql_{entry.name}\({args}\);", proto), entry.name
        assert f"void ql_{entry.name}(" in files[entry.wrapper]
    assert c_sources() == ("control_step.c", "quadland.c", "quadland_status.c")
    assert c_sources(("plant",)) == ("control_step.c", "plant.c", "quadland.c",
                                     "quadland_model.c", "quadland_status.c")
    assert c_sources(("landing_step",)) == ("landing_step.c", "landing_guidance.c",
                                            "quadland_landing.c", "quadland_status.c")
    assert c_sources(("vehicle",))[-2:] == ("quadland_landing_model.c", "quadland_status.c")
    assert c_sources(("estimator_step",)) == ("estimator_step.c", "estimator_init.c",
                                              "quadland_estimator.c", "quadland_status.c")
    assert c_sources(("land_detector",)) == ("land_detector.c", "land_detector_cues.c",
                                             "quadland_land_detector.c", "quadland_status.c")


def test_example_columns_are_the_trajectory_names(files):
    names = [n for n, _ in example_columns(100)]
    quad = {"u1", "v1", "w1", "p1", "q1", "r1"}          # body rates: the C example only
    assert set(names) - set(TRAJECTORY.element_names()) == quad | {"n_clipped", "status"}
    assert names[-2:] == ["n_clipped", "status"]
    assert len(set(names)) == len(names)
    header = "".join(re.findall(r'printf\("([^"%\\]*)"\);', files["example/fly.c"]))
    assert header == ",".join(names)


def test_land_columns_are_the_landing_trajectory_names(files):
    assert [n for n, _ in land_columns()] == list(LANDING_TRAJECTORY.element_names())
    # generated/ is the highway's, on its sensors: the sensed trajectory's columns
    names = [n for n, _ in land_columns(sensed=True)]
    assert names == list(SENSED_TRAJECTORY.element_names())
    body = files["example/land.c"].partition("static void write_header(void)")[2]
    body = body.partition("\n}\n")[0]
    header = "".join(re.findall(r'printf\("([^"%\\]*)"\);', body))
    assert header == ",".join(names)


# --- checkout, scenarios ---------------------------------------------------------

def test_checkout_is_detected():
    assert codegen.checkout_root() == GENERATED_DIR.parent


def test_outside_a_checkout_codegen_needs_out(tmp_path, monkeypatch, capsys):
    """An installed quadland: site-packages holds quadland/ and symbolic/ only."""
    site = tmp_path / "site-packages"
    (site / "quadland").mkdir(parents=True)
    (site / "symbolic").mkdir()
    monkeypatch.setattr(codegen, "_package_parent", lambda: site)
    assert codegen.checkout_root() is None
    for argv in (["codegen"], ["codegen", "--check"]):
        assert cli_main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("quadland: error: ") and "--out" in err[0]
    assert sorted(p.name for p in site.rglob("*")) == ["quadland", "symbolic"]
    out = tmp_path / "out"
    assert cli_main(["codegen", "--out", str(out)]) == 0
    assert (out / "quadland.h").is_file() and (out / "example" / "fly.c").is_file()
    (site / "pyproject.toml").write_text("")
    (site / "generated").mkdir()
    assert codegen.checkout_root() == site


def test_generated_holds_the_paper_and_highway_scenarios_only(capsys):
    before = {p: p.stat().st_mtime_ns for p in GENERATED_DIR.rglob("*") if p.is_file()}
    assert cli_main(["codegen", "--set", "rbf.nodes=7"]) == 2
    assert "--out" in capsys.readouterr().err
    for argv in (["--scenario", "ship"], ["--scenario", "highway", "--set", "rbf.nodes=7"]):
        assert cli_main(["codegen", *argv]) == 2
        assert "--out" in capsys.readouterr().err
    assert cli_main(["codegen", "--scenario", "highway", "--check"]) == 0
    assert before == {p: p.stat().st_mtime_ns for p in GENERATED_DIR.rglob("*") if p.is_file()}


def test_codegen_for_a_scenario_file(tmp_path, capsys):
    paper = load_scenario("paper")
    text = open(paper.source).read().replace('name = "paper"', 'name = "mine"')
    text = re.sub(r"(?m)^nodes = \d+", "nodes = 7", text)
    (tmp_path / "mine.toml").write_text(text)
    out = tmp_path / "gen"
    argv = ["codegen", "--scenario", str(tmp_path / "mine.toml"), "--set",
            "simulation.duration=2.0", "--out", str(out)]
    assert cli_main(argv) == 0
    assert cli_main(argv + ["--check"]) == 0
    h = (out / "quadland.h").read_text()
    assert re.search(r"#define QL_RBF_NODES 7 ", h)
    assert "scenario mine --set simulation.duration=2.0" in h
    assert str(tmp_path) not in "".join(p.read_text() for p in out.rglob("*") if p.is_file())
    assert "#define QL_EXAMPLE_DURATION 2.0 " in (out / "example" / "scenario.h").read_text()
    assert cli_main(["codegen", "--scenario", "nope", "--out", str(out)]) == 2
    assert "unknown scenario" in capsys.readouterr().err


def test_stale_generated_files_are_removed(tmp_path, files):
    codegen.write(tmp_path, files)
    old = tmp_path / "example" / "paper_scenario.h"      # an earlier generation's file,
    old.write_text("/* Do not edit: regenerate with `quadland codegen`. */\n")
    manifest = tmp_path / codegen.MANIFEST                # listed in its manifest
    manifest.write_text(manifest.read_text() + "example/paper_scenario.h\n")
    mine = tmp_path / "notes.txt"
    mine.write_text("mine\n")
    assert "--- a/example/paper_scenario.h" in codegen.diff(tmp_path, files)
    assert "example/paper_scenario.h" in codegen.write(tmp_path, files)
    assert not old.exists() and mine.exists()
    assert codegen.diff(tmp_path, files) == ""


# --- structs, prefixes ---------------------------------------------------------------

def _run_c(tmp_path, source, includes, sources=(), name="prog"):
    cc = _compiler()
    (tmp_path / f"{name}.c").write_text(source)
    exe = tmp_path / name
    proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O0",
                           *[f"-I{i}" for i in includes], "-o", str(exe),
                           str(tmp_path / f"{name}.c"), *map(str, sources), "-lm"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout


@pytest.mark.parametrize("precision", ["double", "float"])
def test_structs_match_the_layouts_and_the_ctypes_mirrors(tmp_path, precision):
    """sizeof and offsetof of every member, from the compiler, against the layouts."""
    config = CodegenConfig(precision)
    ql = config.prefix
    lines = []
    structs = (*api_structs(100), *landing_api_structs(10), *estimator_api_structs(),
               *land_detector_api_structs())
    for s in structs:
        lines.append(f'    printf("{s.name} . %lu\\n", (unsigned long)sizeof({ql}{s.name}));')
        lines.extend(f'    printf("{s.name} {f.name} %lu\\n", '
                     f'(unsigned long)offsetof({ql}{s.name}, {f.name}));'
                     for f in s.layout.fields)
    prog = ("#include <stddef.h>\n#include <stdio.h>\n#include \"quadland_land_detector.h\"\n\n"
            "int main(void)\n{\n" + "\n".join(lines) + "\n    return 0;\n}\n")
    folder = GENERATED_DIR / ("float" if config.is_float else "")
    out = _run_c(tmp_path, prog, [folder])
    got = {(a, b): int(c) for a, b, c in (line.split() for line in out.splitlines())}
    real = ctypes.c_double if precision == "double" else ctypes.c_float
    size = ctypes.sizeof(real)
    for s in structs:
        mirror = flightcode.ctypes_struct(s.layout, real)
        assert ctypes.sizeof(mirror) == got[s.name, "."], s.name
        offsets, n_int = s.layout.offsets(), 0
        for f in s.layout.fields:
            if f.ctype == "real":
                want = offsets[f.name][0] * size
            else:
                want = s.layout.size * size + n_int * ctypes.sizeof(ctypes.c_int)
                n_int += 1
            assert got[s.name, f.name] == want == getattr(mirror, f.name).offset, \
                (s.name, f.name)
        if n_int == 0:
            assert got[s.name, "."] == s.layout.size * size, s.name


_BOTH = r"""#include <stdio.h>
#include <string.h>

#include "double/quadland_landing.h"
#include "float/quadland_landing.h"

int main(void)
{
    static ql_params p;
    static qlf_params pf;
    static ql_adaptive_state s;
    static qlf_adaptive_state sf;
    static ql_landing_params lp;
    static qlf_landing_params lpf;
    ql_quadrotor_state xq = {1.5, {0.5, 0.5, 0.5}, {1.0, 1.0, 0.1}, {0.1, 0.1, 0.1}};
    qlf_quadrotor_state xqf = {1.5f, {0.5f, 0.5f, 0.5f}, {1.0f, 1.0f, 0.1f}, {0.1f, 0.1f, 0.1f}};
    ql_vehicle_state yv = {0.0, 0.25, 0.0};
    qlf_vehicle_state yvf = {0.0f, 0.25f, 0.0f};
    ql_reference r;
    qlf_reference rf;
    ql_output o;
    qlf_output of;
    ql_landing_measurement y;
    qlf_landing_measurement yf;
    ql_guidance_params gp;
    qlf_guidance_params gpf;
    ql_guidance_cues gc = {0.0, 0.0, 0.0};
    qlf_guidance_cues gcf = {0.0f, 0.0f, 0.0f};
    ql_guidance_state gs;
    qlf_guidance_state gsf;
    ql_position_reference pr;
    qlf_position_reference prf;
    ql_landing_state ls;
    qlf_landing_state lsf;
    ql_landing_output lo;
    qlf_landing_output lof;
    ql_status a, c, d;
    qlf_status b, cf, df;
    ql_params_init(&p);
    qlf_params_init(&pf);
    ql_reference_init(&r);
    qlf_reference_init(&rf);
    ql_adaptive_state_init(&s);
    qlf_adaptive_state_init(&sf);
    a = ql_control_step(&xq, &yv, &r, &p, 0.002, &s, &o);
    b = qlf_control_step(&xqf, &yvf, &rf, &pf, 0.002f, &sf, &of);
    memset(&y, 0, sizeof y);
    memset(&yf, 0, sizeof yf);
    y.p_e[2] = 3.0;     /* at the hover point, level */
    yf.p_e[2] = 3.0f;
    ql_landing_params_init(&lp);
    qlf_landing_params_init(&lpf);
    ql_guidance_params_init(&gp);
    qlf_guidance_params_init(&gpf);
    ql_guidance_state_init(&gs, &gp);
    qlf_guidance_state_init(&gsf, &gpf);
    ql_landing_state_init(&ls, &y);
    qlf_landing_state_init(&lsf, &yf);
    c = ql_guidance_step(&y, &gc, &gp, 0.004, &gs, &pr);
    cf = qlf_guidance_step(&yf, &gcf, &gpf, 0.004f, &gsf, &prf);
    d = ql_landing_step(&y, &pr, &lp, 0.004, &ls, &lo);
    df = qlf_landing_step(&yf, &prf, &lpf, 0.004f, &lsf, &lof);
    printf("%d %d %d %d %d %d %.17g %.17g %.17g %.17g %d %d %d %d\n", (int)a, (int)b, (int)c,
           (int)cf, (int)d, (int)df, o.rotor[0], (double)of.rotor[0], lo.F_cmd[0],
           (double)lof.F_cmd[0], QL_RBF_NODES, QLF_RBF_NODES, QL_LANDING_RBF_NODES,
           gs.phase);
    return a != QL_OK || b != QLF_OK || c != QL_OK || cf != QLF_OK || d != QL_OK || df != QLF_OK;
}
"""


@pytest.mark.slow
def test_double_and_float_builds_link_into_one_program(tmp_path):
    import shutil

    sources = (*c_sources(), *c_sources(("landing_step",)), *c_sources(("estimator_step",)),
               *c_sources(("land_detector",)))
    for name, folder in (("double", GENERATED_DIR), ("float", GENERATED_DIR / "float")):
        shutil.copytree(folder, tmp_path / name, ignore=shutil.ignore_patterns("example"))
    units = [tmp_path / p / f for p in ("double", "float") for f in dict.fromkeys(sources)]
    out = _run_c(tmp_path, _BOTH, [tmp_path], units).split()
    assert out[:6] == ["0"] * 6
    rd, rf, Fd, Ff = (float(v) for v in out[6:10])
    assert out[10:] == ["100", "100", "10", "1"]        # the hover point: the approach is over
    assert rf == pytest.approx(rd, rel=1e-4) and Ff == pytest.approx(Fd, rel=1e-4)
    assert 0 < Fd < 9.8                                   # hover thrust within [0, F_max]
    if shutil.which("nm") is None:
        return
    cc = _compiler()
    symbols = []
    for unit in units:
        obj = unit.with_suffix(".o")
        subprocess.run([cc, "-std=c99", "-O0", "-c", str(unit), "-o", str(obj)], check=True)
        nm = subprocess.run(["nm", "-g", "--defined-only", str(obj)], capture_output=True,
                            text=True, check=True).stdout
        prefix = "qlf_" if "float" in unit.parts else "ql_"
        names = [line.split()[-1] for line in nm.splitlines() if line.strip()]
        assert names and all(n.startswith(prefix) for n in names), (unit, names)
        symbols += names
    assert len(symbols) == len(set(symbols))


def test_float_header_spells_ql_names_alone_and_refuses_a_collision(tmp_path):
    cc = _compiler()

    def syntax(text, *includes):
        (tmp_path / "t.c").write_text(text)
        return subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror",
                               "-fsyntax-only", *[f"-I{i}" for i in includes],
                               str(tmp_path / "t.c")], capture_output=True, text=True)

    example = GENERATED_DIR / "example"
    for src in ("fly.c", "bench.c", "land.c"):
        proc = syntax((example / src).read_text(), GENERATED_DIR / "float", example)
        assert proc.returncode == 0, proc.stderr
    header = (GENERATED_DIR / "float" / "quadland.h").read_text()
    body = header.partition("#if !defined(QL_QUADLAND_H)")[0]
    declared = set(re.findall(r"\b(?:qlf|QLF)_\w+", body))
    declared -= {"QLF_QUADLAND_H", "QLF_NO_QL_NAMES"}
    aliased = set(re.findall(r"#define (?:ql|QL)_\w+ ((?:qlf|QLF)_\w+)", header))
    assert declared == aliased
    landing = (GENERATED_DIR / "float" / "quadland_landing.h").read_text()
    body = landing.partition("#ifdef QLF_QL_NAMES")[0].partition('#include "quadland.h"')[2]
    declared = set(re.findall(r"\b(?:qlf|QLF)_\w+", body)) - {"QLF_QUADLAND_LANDING_H"}
    assert declared and declared <= set(re.findall(r"#define (?:ql|QL)_\w+ ((?:qlf|QLF)_\w+)",
                                                   landing))
    estimator = (GENERATED_DIR / "float" / "quadland_estimator.h").read_text()
    body = estimator.partition("#ifdef QLF_QL_NAMES")[0]
    body = body.partition('#include "quadland_landing.h"')[2]
    declared = set(re.findall(r"\b(?:qlf|QLF)_\w+", body)) - {"QLF_QUADLAND_ESTIMATOR_H"}
    assert "qlf_estimator_step" in declared and declared <= set(re.findall(
        r"#define (?:ql|QL)_\w+ ((?:qlf|QLF)_\w+)", estimator))
    detector = (GENERATED_DIR / "float" / "quadland_land_detector.h").read_text()
    body = detector.partition("#ifdef QLF_QL_NAMES")[0]
    body = body.partition('#include "quadland_estimator.h"')[2]
    declared = set(re.findall(r"\b(?:qlf|QLF)_\w+", body)) - {"QLF_QUADLAND_LAND_DETECTOR_H"}
    assert "qlf_land_detector_step" in declared and declared <= set(re.findall(
        r"#define (?:ql|QL)_\w+ ((?:qlf|QLF)_\w+)", detector))
    g = GENERATED_DIR
    proc = syntax(f'#include "{g}/float/quadland.h"\n#include "{g}/quadland.h"\n'
                  "int main(void) { return 0; }\n")
    assert proc.returncode != 0 and "include this (double) header first" in proc.stderr


def test_any_node_count_compiles_alone(tmp_path):
    cc = _compiler()
    d = paper_defaults(load_scenario("paper", ["rbf.nodes=3"]))
    for config in (CodegenConfig(), CodegenConfig("float")):
        files = generate(d, config)
        assert "#define " + config.macro_prefix + "RBF_NODES 3 " in files["quadland.h"]
        folder = tmp_path / config.precision
        folder.mkdir()
        for name, text in files.items():
            (folder / name).write_text(text)
        for name in ("quadland.c", "control_step.c", "quadland_model.c"):
            proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror",
                                   "-fsyntax-only", f"-I{folder}", str(folder / name)],
                                  capture_output=True, text=True)
            assert proc.returncode == 0, proc.stderr
    d = landing_defaults(load_scenario("highway", ["rbf.nodes=3"]))
    for config in (CodegenConfig(), CodegenConfig("float")):
        files = generate_landing(d, config)
        assert "#define " + config.macro_prefix + "LANDING_RBF_NODES 3 " in \
            files["quadland_landing.h"]
        folder = tmp_path / config.precision
        for name, text in files.items():
            (folder / name).write_text(text)
        for name in ("quadland_landing.c", "landing_step.c"):
            proc = subprocess.run([cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror",
                                   "-fsyntax-only", f"-I{folder}", str(folder / name)],
                                  capture_output=True, text=True)
            assert proc.returncode == 0, proc.stderr


def test_the_tree_has_exactly_its_parts():
    """generate_tree takes one C-defaults object per part and refuses any other set,
    so a part cannot be dropped or an extra one ignored without a word."""
    from quadland.codegen import tree_defaults
    from quadland_symbolic.codegen import TREE_PARTS, generate_tree

    parts = tree_defaults()
    assert set(parts) == set(TREE_PARTS)
    with pytest.raises(ValueError, match="parts are paper, landing, got paper$"):
        generate_tree({"paper": parts["paper"]})
    with pytest.raises(ValueError, match="got paper, landing, glider"):
        generate_tree({**parts, "glider": parts["paper"]})


def test_a_kind_without_a_part_in_the_tree_is_one_line(monkeypatch):
    """A loop kind that generates no flight code is refused by name, not ignored."""
    import types

    import quadland.codegen as qcodegen
    from quadland.exceptions import CodegenError

    glider = types.SimpleNamespace(name="glider", codegen_part=None)
    monkeypatch.setattr(qcodegen, "kind_of", lambda scenario: glider)
    sc = types.SimpleNamespace(model="glider")
    with pytest.raises(CodegenError, match="^--scenario: the loop kind 'glider' has no part in "
                                           "the generated tree"):
        qcodegen.tree_defaults(sc)
