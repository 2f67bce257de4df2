"""The simulators compiled for the machine's own instructions (issue 20): AVX2 where the
CPU has it, keyed apart, the baseline where the compiler refuses, and the same bits.

``quadland.engine.machine.machine_flags`` adds ``-mavx2`` (no FMA, no contraction) to
the runtime's simulators. The landings flown on such a build are compared with the
baseline build's (the flags every x86-64 has, as every simulator was built before),
every column and state bit for bit.
"""

from __future__ import annotations

import ctypes
import hashlib
import stat
import textwrap

import numpy as np
import pytest

import quadland
from quadland.engine import build, machine, recall
from quadland.engine.compiled import compiled_loop
from quadland_symbolic.paper_loop import paper_loop_recipe

pytestmark = pytest.mark.skipif(not build.have_compiler(), reason="needs a C compiler")

#: A unit that tells whether it was compiled for AVX2 (gcc and clang define __AVX2__
#: under -mavx2) and for FMA; returning a constant needs no AVX2 to run.
PROBE = textwrap.dedent("""\
    int probe_avx2(void)
    {
    #ifdef __AVX2__
        return 1;
    #else
        return 0;
    #endif
    }
    int probe_fma(void)
    {
    #ifdef __FMA__
        return 1;
    #else
        return 0;
    #endif
    }
    int probe_math(void)
    {
    #if defined(__FAST_MATH__)
        return 2;
    #elif defined(__NO_MATH_ERRNO__)
        return 1;
    #else
        return 0;
    #endif
    }
    """)

GCC = ("/usr/bin/cc\ncc (Debian 12.2.0-14+deb12u1) 12.2.0\nCopyright (C) 2022 Free Software "
       "Foundation, Inc.")
CLANG = "/usr/bin/clang\nDebian clang version 14.0.6\nTarget: x86_64-pc-linux-gnu"
TCC = "/usr/bin/tcc\ntcc version 0.9.27 (x86_64 Linux)"
MACHINE = (*machine.AVX2_FLAGS, *machine.ERRNO_FLAGS, *machine.VECTOR_FLAGS)
AVX2_CPU = frozenset("fpu sse sse2 ssse3 sse4_1 sse4_2 avx fma avx2".split())
OLD_CPU = frozenset("fpu sse sse2 ssse3 sse4_1 sse4_2 avx".split())


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A private cache folder for the test."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    return tmp_path / "xdg" / "quadland"


@pytest.mark.parametrize("arch,identity,cpu,flags", [
    ("x86_64", GCC, AVX2_CPU, MACHINE),
    ("x86_64", CLANG, AVX2_CPU, machine.AVX2_FLAGS),  # errno's bits measured on GCC only
    ("AMD64", GCC, AVX2_CPU, MACHINE),
    ("x86_64", GCC, OLD_CPU, ()),                  # AVX without AVX2
    ("x86_64", GCC, frozenset(), ()),              # no /proc/cpuinfo
    ("x86_64", TCC, AVX2_CPU, ()),                 # neither GCC nor clang
    ("aarch64", GCC, AVX2_CPU, ()),
    ("arm64", CLANG, AVX2_CPU, ())])
def test_the_machine_flags_follow_the_cpu_and_the_compiler(monkeypatch, arch, identity, cpu,
                                                           flags):
    monkeypatch.setattr(machine.platform, "machine", lambda: arch)
    monkeypatch.setattr(machine, "compiler_identity", lambda cc: identity)
    monkeypatch.setattr(machine, "cpu_flags", lambda: cpu)
    assert machine.machine_flags("cc") == flags


def test_the_flags_are_avx2_without_fma_nor_contraction():
    assert machine.AVX2_FLAGS == ("-mavx2", "-mno-fma", "-ffp-contract=off")
    assert machine.ERRNO_FLAGS == ("-fno-math-errno",)
    # the vectorizer's cost model alone: neither -O3's other passes nor reassociation
    assert machine.VECTOR_FLAGS == ("-fvect-cost-model=dynamic",)


def test_the_cpu_flags_are_the_first_flags_line(tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nvendor_id\t: AuthenticAMD\nflags\t\t: fpu sse2 avx avx2\n"
                    "bugs\t\t: sysret_ss_attrs\n\nprocessor\t: 1\nflags\t\t: fpu\n")
    assert machine.cpu_flags(info) == frozenset({"fpu", "sse2", "avx", "avx2"})
    assert machine.cpu_flags(tmp_path / "missing") == frozenset()


def _probe_library(strict: bool = False):
    return build.build_library({"probe.c": PROBE}, ("probe.c",), name="libprobe", strict=strict)


@pytest.mark.skipif(not (build.have_compiler() and machine.machine_flags(build.find_compiler())),
                    reason="the machine has no AVX2 (or no GCC or clang on x86-64)")
def test_the_simulators_compile_for_the_machine_and_are_keyed_apart(cache, monkeypatch):
    monkeypatch.setattr(build, "machine_flags", lambda cc: MACHINE)
    mine = _probe_library()
    lib = ctypes.CDLL(str(mine))
    # AVX2, no FMA; libm without errno but not fast math (no libmvec declarations)
    assert (lib.probe_avx2(), lib.probe_fma(), lib.probe_math()) == (1, 0, 1)
    strict = ctypes.CDLL(str(_probe_library(strict=True)))  # flight code: the baseline
    assert strict.probe_avx2() == 0
    monkeypatch.setattr(build, "machine_flags", lambda cc: ())
    baseline = _probe_library()
    assert baseline.parent != mine.parent
    assert ctypes.CDLL(str(baseline)).probe_avx2() == 0


def test_the_recipe_key_names_the_machine_flags(monkeypatch):
    recipe = paper_loop_recipe(2)

    def key():
        return recall.recall_key(recipe, "continuous", None, (), "qlsim_paper_continuous",
                                 "-O2", False)

    monkeypatch.setattr(build, "machine_flags", lambda cc: machine.AVX2_FLAGS)
    avx2 = key()
    monkeypatch.setattr(build, "machine_flags", lambda cc: ())
    assert key() != avx2


@pytest.mark.parametrize("refused, flags", [("-mavx2", machine.AVX2_FLAGS),
                                             ("-fvect-cost-model=dynamic", MACHINE)])
def test_a_compiler_that_refuses_them_builds_the_baseline(cache, tmp_path, monkeypatch,
                                                          refused, flags):
    """A compiler for another target refuses -mavx2, an older GCC the vectorizer's cost
    model (as gcc's ``cc1: error: unrecognized command-line option``): the library is built
    without the machine's flags, once."""
    real = build.find_compiler()
    log = tmp_path / "calls"
    fake = tmp_path / "fakecc"
    fake.write_text(textwrap.dedent(f"""\
        #!/bin/sh
        echo "$*" >> {log}
        for a in "$@"; do
            if [ "$a" = "{refused}" ]; then
                echo "cc1: error: unrecognized command-line option '{refused}'" >&2
                exit 1
            fi
        done
        exec {real} "$@"
        """))
    fake.chmod(fake.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("CC", str(fake))
    monkeypatch.setattr(build, "machine_flags", lambda cc: flags)
    lib = ctypes.CDLL(str(_probe_library()))
    assert lib.probe_avx2() == 0
    compiles = [line for line in log.read_text().splitlines() if " -c " in f" {line} "]
    assert len(compiles) == 2 and refused in compiles[0]
    assert not any(f in compiles[1] for f in flags)


def test_another_compiler_error_is_not_retried(cache, monkeypatch):
    monkeypatch.setattr(build, "machine_flags", lambda cc: machine.AVX2_FLAGS)
    calls = []
    real = build.run_compilers

    def counting(cmds, *args, **kwargs):
        calls.append(cmds)
        return real(cmds, *args, **kwargs)

    monkeypatch.setattr(build, "run_compilers", counting)
    with pytest.raises(build.CompileError, match="failed on the generated C"):
        build.build_library({"bad.c": "int f(void) { return }\n"}, ("bad.c",), name="libbad",
                            strict=False)
    assert len(calls) == 1


def _landing_digest(scenario: str) -> str:
    result = quadland.simulate(quadland.load_scenario(scenario))
    digest = hashlib.sha256()
    for name in result.columns:
        digest.update(name.encode() + b"\0" + np.ascontiguousarray(result[name]).tobytes())
    digest.update(np.ascontiguousarray(result.states).tobytes())
    return digest.hexdigest()


@pytest.mark.slow
@pytest.mark.skipif(not (build.have_compiler() and machine.machine_flags(build.find_compiler())),
                    reason="the machine has no AVX2 (or no GCC or clang)")
@pytest.mark.parametrize("scenario", ["highway", "ship", "turning", "highway_100", "ship_ss5"])
def test_the_landings_on_the_machines_build_are_the_baselines_bits(monkeypatch, scenario):
    """Every column and state of the default landing, on the AVX2 build and on the
    baseline's (built, or loaded from the user's cache, beside it)."""
    compiled_loop.cache_clear()
    try:
        mine = _landing_digest(scenario)
        monkeypatch.setattr(build, "machine_flags", lambda cc: ())
        compiled_loop.cache_clear()
        baseline = _landing_digest(scenario)
    finally:
        compiled_loop.cache_clear()
    assert mine == baseline
