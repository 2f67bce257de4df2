"""The instructions the runtime's simulators compile for: the machine's own where they
give the baseline's bits.

The runtime builds its simulators on the user's machine (:mod:`quadland.engine.build`),
so it may use the machine's vector instructions. :func:`machine_flags` adds AVX2
(:data:`AVX2_FLAGS`) on an x86-64 CPU that has it, with GCC or clang: the scalar C then
uses the VEX encodings (three-operand arithmetic, no false dependencies on a
register's upper half) and 256-bit moves: 2.5 to 6 % less CPU a flight (measured in
``docs/performance.md``, "The compiled flight's instructions"); libm's functions
without ``errno`` (:data:`ERRNO_FLAGS`, 1.9 % fewer instructions); and GCC's loop
vectorizer's dynamic cost model (:data:`VECTOR_FLAGS`, 5 % fewer). Every operation stays
the IEEE operation it was: no fused multiply-add (``-mno-fma``; GCC 12 vectorizes an
add-and-subtract pair into ``vfmsubadd`` with FMA enabled even under
``-ffp-contract=off``, which changed a highway landing's bits, so ``-march=x86-64-v3``
and ``-march=native`` are not used), no contraction, no fast math. The flags are in the
libraries' keys (:func:`quadland.engine.build.build_library`,
:func:`quadland.engine.recall.recall_key`): a cache shared by machines of different
CPUs keeps a library for each. A compiler that rejects them (one for another target)
builds at the baseline (:func:`machine_rejected`).
"""

from __future__ import annotations

import functools
import platform
from pathlib import Path

from quadland.engine.compiler import compiler_identity

__all__ = ["AVX2_FLAGS", "CPUINFO", "ERRNO_FLAGS", "VECTOR_FLAGS", "cpu_flags",
           "machine_flags", "machine_rejected"]

#: The flags of an x86-64 CPU with AVX2: its instructions, without FMA, and no
#: contraction of a product and a sum (``-std=c99`` implies it; said explicitly).
AVX2_FLAGS = ("-mavx2", "-mno-fma", "-ffp-contract=off")
#: libm's functions as pure functions of their arguments: no ``errno`` (the simulators never
#: read it), so gcc merges, moves and drops their calls as it does arithmetic, and computes
#: ``sqrt`` inline without its error branch; a value is what the call returns for its
#: argument either way, the same bits (1.9 % fewer instructions a ``highway`` flight,
#: docs/performance.md, "eleventh").
#: It is not fast math: ``__FAST_MATH__`` stays undefined, so glibc declares no vector
#: variants of libm's functions (``bits/math-vector.h``), whose bits differ.
ERRNO_FLAGS = ("-fno-math-errno",)
#: GCC's loop vectorizer with its dynamic cost model (at -O2 it uses the "very cheap"
#: one, which leaves a loop of a count known only at run time scalar): the driver's RK4
#: and finiteness loops and CasADi's ``casadi_copy`` loops become vector loops with a
#: check that their arrays do not overlap. Element by element the same operations (GCC
#: vectorizes no floating-point sum without ``-fassociative-math``): the same bits, 5 %
#: fewer instructions a ``highway`` flight (docs/performance.md, "eighteenth").
VECTOR_FLAGS = ("-fvect-cost-model=dynamic",)
#: Where Linux lists the CPU's features.
CPUINFO = Path("/proc/cpuinfo")


@functools.cache
def cpu_flags(path: Path = CPUINFO) -> frozenset[str]:
    """The CPU's features as the kernel lists them (the first ``flags`` line of
    ``/proc/cpuinfo``; the kernel leaves out AVX where the system does not save its
    registers); empty where there is no such file (not Linux)."""
    try:
        with open(path, encoding="ascii", errors="replace") as fh:
            for line in fh:
                name, _, value = line.partition(":")
                if name.strip() == "flags":
                    return frozenset(value.split())
    except OSError:
        pass
    return frozenset()


def machine_flags(cc: str) -> tuple[str, ...]:
    """The machine's own flags for compiler ``cc``: :data:`AVX2_FLAGS`,
    :data:`ERRNO_FLAGS` and :data:`VECTOR_FLAGS` on an x86-64 CPU with AVX2 and a GCC (by
    its ``--version``), the AVX2 flags alone with a clang, none otherwise."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return ()
    identity = compiler_identity(cc)
    if "Free Software Foundation" not in identity and "clang" not in identity.lower():
        return ()
    if not {"avx", "avx2"} <= cpu_flags():
        return ()
    # -fno-math-errno's same bits are measured with GCC only (clang turns libm's calls
    # into intrinsics it may fold): clang gets the AVX2 flags alone
    gcc = "Free Software Foundation" in identity
    return (*AVX2_FLAGS, *ERRNO_FLAGS, *VECTOR_FLAGS) if gcc else AVX2_FLAGS


def machine_rejected(message: str, flags: tuple[str, ...]) -> bool:
    """Whether a compiler's error ``message`` is about one of the machine's ``flags``
    (a compiler for another target): the build is then made at the baseline."""
    return any(flag in message for flag in flags)
