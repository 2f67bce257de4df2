"""A Function composed of stages as one C translation unit per stage.

CasADi writes an MX Function and every Function it calls into one file. A loop's
controller composed of stages (:attr:`quadland_symbolic.loop.LoopModel.controller_stages`,
:class:`quadland_symbolic.stages.Staged`) would be one file of over a megabyte (the
sensed landing loop's), which gcc compiles at -O2 only beyond the build's memory and
time budgets (``quadland.engine.build.COMPILE_FIT``). :func:`staged_sources` writes
each stage as CasADi writes it, one file each, and the composed function's own C: each
stage called in turn with the caller's conventions (``arg``, ``res``, ``iw``, ``w``), as
CasADi's MX code calls a Function, its inputs and outputs in place where they are
slices of the composed function's (no copies), the other values between the stages in
its real work array.

A delay line of the stages (:attr:`quadland_symbolic.stages.Staged.rings`) is not
shifted: its shift's stage is left out, and the caller passes after the composed
function's outputs one more pointer a ring, ``res[n_out + i]``, where the line's
next record goes and its ``n`` slots follow, newest first (a ring whose slots the
caller keeps twice over, so that the line from any slot on is contiguous:
``symbolic/templates/simulator.c.jinja``). The composed function then writes
neither that line's piece of its output nor a copy of it: one record a ring and
call instead of the whole line.

Inputs constant over a flight (``constants``: the controller's parameters) make a stage's
values of them alone the same at every call. Such an SX stage is cut in two by
:func:`~quadland_symbolic.codegen.time_split.time_split` on those inputs: its values of the
constants alone in ``<name>_<stage>_params``, which ``<name>_params`` (the composed
function's inputs, its one output those values of every cut stage) computes once, and the
core, which reads them where the caller passes them, ``arg[n_in]``. The same instructions
on the same operands: the same bits, the values given what ``<name>_params`` returns for
the same constants.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.codegen.time_split import HOISTED, time_split

__all__ = ["CUT_PARAMS", "FREE_STAGES", "MIN_PARAMS", "staged_sources"]

#: The fewest instructions of a stage's values of the constants alone worth cutting it
#: for (one more pointer a call, a few values read from memory).
MIN_PARAMS = 32
#: Whether stages are cut on their constant inputs at all. The cache's keys hash this
#: module's text, not the value: a build with it turned off at run time (the benchmark's
#: and the tests' uncut build) needs a model of another name.
CUT_PARAMS = True
#: Whether the stages' free functions are written and called where the caller asks
#: (``staged_sources``' ``free``); off, the stages alone, as before (the benchmark's and
#: the tests' build without them: a model of another name, as for :data:`CUT_PARAMS`).
FREE_STAGES = True


def _dense(f: ca.Function) -> None:
    for kind, n, sp in (("input", f.n_in(), f.sparsity_in), ("output", f.n_out(), f.sparsity_out)):
        for i in range(n):
            if not sp(i).is_dense() or sp(i).size2() != 1:
                raise ValueError(f"stage {f.name()}: {kind} {i} is not a dense column")


def _places(staged, name: str) -> tuple[dict, int]:
    """Where each named value is, as a C expression; and the reals of ``w`` they take.

    An input's slice is read in place; a piece of an output is written in place
    (in ``w`` if the caller passes no output there); any other value is in ``w``.
    """
    size = {n: k for n, k in staged.inputs}
    for stage in staged.stages:
        _dense(stage)
        size.update((n, stage.nnz_out(i)) for i, n in enumerate(stage.name_out()))
    index = {n: i for i, (n, _) in enumerate(staged.inputs)}
    where = {n: f"arg[{i}]" for n, i in index.items()}
    for n, src, start, _ in staged.slices:
        where[n] = f"(arg[{index[src]}] ? arg[{index[src]}] + {start} : 0)"
    for i, (line, record, _) in enumerate(staged.rings):   # the caller's ring
        where[line] = where[record] = f"res[{len(staged.outputs) + i}]"
    total = 0
    for k, (_, pieces) in enumerate(staged.outputs):
        offset = 0
        for n in pieces:
            if n not in where:
                where[n] = f"(res[{k}] ? res[{k}] + {offset} : w + {total})"
                total += size[n]
            offset += size[n]
    for stage in staged.stages:
        for n in stage.name_out():
            if n not in where:
                where[n] = f"w + {total}"
                total += size[n]
    return where, total


def _cut(stage: ca.Function, constant: set):
    """``(core, params)`` of an SX ``stage`` by :func:`time_split` on its inputs in
    ``constant``, or ``None`` (nothing of them alone, fewer than :data:`MIN_PARAMS`
    instructions, an MX stage)."""
    names = [n for n in stage.name_in() if n in constant]
    if not names or not stage.is_a("SXFunction"):
        return None
    split = time_split(stage, tuple(names))
    if split is None or split[1].n_instructions() < MIN_PARAMS:
        return None
    return split


def _constant_names(staged, constants) -> set:
    """The named values constant over a flight: ``constants`` and their slices."""
    return set(constants) | {n for n, src, _, _ in staged.slices if src in constants}


def _call(where, fname, core, total) -> list:
    """The lines calling stage function ``fname`` (``core``) on its named values."""
    return ([f"    arg1[{i}] = {where[n]};" for i, n in enumerate(core.name_in())]
            + [f"    res1[{i}] = {where[n]};" for i, n in enumerate(core.name_out())]
            + [f"    if ({fname}(arg1, res1, iw, w + {total}, 0)) return 1;"])


def _params_call(where, fname, params, at) -> list:
    """The lines computing a cut stage's values of the constants alone into ``res[0]``."""
    return ([f"    arg1[{i}] = {where[n]};" for i, n in enumerate(params.name_in())]
            + [f"    res1[0] = res[0] ? res[0] + {at} : 0;",
               f"    if ({fname}(arg1, res1, iw, w, 0)) return 1;"])


def _branch(flag, calls) -> list:
    """A stage's call, or its free function's where the caller's ``flag`` is not zero."""
    if len(calls) == 1:
        return calls[0]
    return ([f"    if ({flag} && {flag}[0] != 0) {{"] + ["    " + c for c in calls[1]]
            + ["    } else {"] + ["    " + c for c in calls[0]] + ["    }"])


def staged_sources(prefix: str, staged, emit, constants=(), free: bool = False
                   ) -> tuple[dict, dict]:
    """The C of ``staged`` (named ``<prefix><its name>``), one file a stage.

    Parameters
    ----------
    prefix : str
        The simulator's symbol prefix.
    staged : quadland_symbolic.stages.Staged
        Every input and output of its stages a dense column.
    emit : callable
        ``emit(name, f) -> {file: text}``: CasADi's C of ``f`` named ``name``.
    constants : tuple of str
        Inputs the caller holds constant over its calls (module docstring).
    free : bool
        Whether the caller flags where the gear is far from the deck: the stages'
        :attr:`~quadland_symbolic.stages.Staged.free` functions (``<name>_<stage>_free``),
        called instead where ``arg[n_in]`` (after the constants', ``arg[n_in + 1]``) is not 0.

    Returns
    -------
    files : dict of str to str
        Each stage's files (``<prefix><name>_<stage>.c/.h``), ``<prefix><name>.c/.h``
        and, where stages are cut, ``<prefix><name>_<stage>_params.c/.h``.
    sizes : dict of str to int
        ``sz_arg``, ``sz_res``, ``sz_iw``, ``sz_w`` of the composed function and of
        ``<prefix><name>_params``; ``n_params``: the values it computes (0: none, no
        such function, and the composed function reads no ``arg[n_in]``).
    """
    shifts = {line for line, _, _ in staged.rings}
    name = prefix + staged.name
    stages = tuple(s for s in staged.stages if not shifts & set(s.name_out()))
    variants = dict(staged.free) if free and FREE_STAGES else {}
    constant = _constant_names(staged, constants) if CUT_PARAMS else set()
    cuts = {s.name(): _cut(s, constant) for s in stages}
    cuts.update((f"{n}_free", _cut(f, constant)) for n, f in variants.items())
    cuts = {k: v for k, v in cuts.items() if v is not None}
    where, total = _places(staged, name)
    n_in, n_res = len(staged.inputs), len(staged.outputs) + len(staged.rings)
    n_extra = n_in + bool(cuts) + bool(variants)
    body = [f"    const casadi_real **arg1 = arg + {n_extra};",
            f"    casadi_real **res1 = res + {n_res};"]
    pbody = [f"    const casadi_real **arg1 = arg + {n_extra};",
             "    casadi_real **res1 = res + 1;"]
    flag = f"arg[{n_in + bool(cuts)}]"
    files, called, at = {}, [], 0
    for stage in stages:
        body.append(f"    /* {stage.name()} */")
        both = [(stage.name(), stage)]
        if stage.name() in variants:
            both.append((f"{stage.name()}_free", variants[stage.name()]))
        calls = []
        for sname, f in both:
            core, params = cuts.get(sname, (f, None))
            where[HOISTED] = f"arg[{n_in}] + {at}"
            files.update(emit(f"{name}_{sname}", core))
            called.append((sname, core))
            calls.append(_call(where, f"{name}_{sname}", core, total))
            if params is not None:
                files.update(emit(f"{name}_{sname}_params", params))
                called.append((f"{sname}_params", params))
                pbody += _params_call(where, f"{name}_{sname}_params", params, at)
                at += params.nnz_out(0)
        body += _branch(flag, calls)
    fns = [f for _, f in called]
    sizes = dict(sz_arg=n_extra + max(f.sz_arg() for f in fns),
                 sz_res=n_res + max(f.sz_res() for f in fns), sz_iw=max(f.sz_iw() for f in fns),
                 sz_w=total + max(f.sz_w() for f in fns), n_params=at,
                 free=bool(variants))
    params = (f" * arg[{n_in}]: the values of the constants alone ({at}), as {name}_params\n"
              f" * computes them from the same {', '.join(constants)}.\n") if cuts else ""
    files.update(_composed(name, staged, stages, called, body, total, params))
    if cuts:
        files[f"{name}.h"] += f"{_signature(name + '_params')};\n"
        files[f"{name}.c"] += (
            f"\n/* The values of {', '.join(constants)} alone of the stages "
            f"{', '.join(cuts)}, into res[0]. */\n"
            f"{_signature(name + '_params')}\n{{\n    (void)mem;\n" + "\n".join(pbody)
            + "\n    return 0;\n}\n")
    return files, sizes


def _signature(name: str) -> str:
    return (f"int {name}(const casadi_real** arg, casadi_real** res, casadi_int* iw, "
            "casadi_real* w, int mem)")


def _composed(name, staged, stages, called, body, total, params) -> dict:
    """``<name>.h`` and ``<name>.c``: the composed function calling its stages."""
    includes = "".join(f'#include "{name}_{c}.h"\n' for c, _ in called)
    rings = "".join(f" * res[{len(staged.outputs) + i}]: the ring of {line} (its record of "
                    "this call there, its slots from there on).\n"
                    for i, (line, _, _) in enumerate(staged.rings))
    return {f"{name}.h": (f"/* {name}: {staged.name} as its stages "
                          f"({', '.join(s.name() for s in stages)}). */\n"
                          f"{includes}{_signature(name)};\n"),
            f"{name}.c": (
                f"/* {name}: {staged.name} as its stages, each in its own file; the values\n"
                f" * between them in place or in w[0..{total}). Generated by\n"
                f" * quadland_symbolic.codegen.staged_c.\n{rings}{params} */\n"
                f'#include "{name}.h"\n\n{_signature(name)}\n{{\n    (void)mem;\n'
                + "\n".join(body) + "\n    return 0;\n}\n")}
