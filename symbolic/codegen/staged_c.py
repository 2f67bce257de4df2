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
"""

from __future__ import annotations

import casadi as ca

__all__ = ["staged_sources"]


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


def staged_sources(prefix: str, staged, emit) -> tuple[dict, dict]:
    """The C of ``staged`` (named ``<prefix><its name>``), one file a stage.

    Parameters
    ----------
    prefix : str
        The simulator's symbol prefix.
    staged : quadland_symbolic.stages.Staged
        Every input and output of its stages a dense column.
    emit : callable
        ``emit(name, f) -> {file: text}``: CasADi's C of ``f`` named ``name``.

    Returns
    -------
    files : dict of str to str
        Each stage's files (``<prefix><name>_<stage>.c/.h``) and ``<prefix><name>.c/.h``.
    sizes : dict of str to int
        ``sz_arg``, ``sz_res``, ``sz_iw``, ``sz_w`` of the composed function.
    """
    shifts = {line for line, _, _ in staged.rings}
    name = prefix + staged.name
    stages = tuple(s for s in staged.stages if not shifts & set(s.name_out()))
    where, total = _places(staged, name)
    n_res = len(staged.outputs) + len(staged.rings)
    body = [f"    const casadi_real **arg1 = arg + {len(staged.inputs)};",
            f"    casadi_real **res1 = res + {n_res};"]
    files = {}
    for stage in stages:
        files.update(emit(f"{name}_{stage.name()}", stage))
        body.append(f"    /* {stage.name()} */")
        body += [f"    arg1[{i}] = {where[n]};" for i, n in enumerate(stage.name_in())]
        body += [f"    res1[{i}] = {where[n]};" for i, n in enumerate(stage.name_out())]
        body.append(f"    if ({name}_{stage.name()}(arg1, res1, iw, w + {total}, 0)) return 1;")
    sizes = dict(sz_arg=len(staged.inputs) + max(s.sz_arg() for s in stages),
                 sz_res=n_res + max(s.sz_res() for s in stages),
                 sz_iw=max(s.sz_iw() for s in stages),
                 sz_w=total + max(s.sz_w() for s in stages))
    signature = (f"int {name}(const casadi_real** arg, casadi_real** res, casadi_int* iw, "
                 "casadi_real* w, int mem)")
    includes = "".join(f'#include "{name}_{s.name()}.h"\n' for s in stages)
    files[f"{name}.h"] = (f"/* {name}: {staged.name} as its stages "
                          f"({', '.join(s.name() for s in stages)}). */\n"
                          f"{includes}{signature};\n")
    rings = "".join(f" * res[{len(staged.outputs) + i}]: the ring of {line} (its record of "
                    "this call there, its slots from there on).\n"
                    for i, (line, _, _) in enumerate(staged.rings))
    files[f"{name}.c"] = (
        f"/* {name}: {staged.name} as its stages, each in its own file; the values\n"
        f" * between them in place or in w[0..{total}). Generated by\n"
        f" * quadland_symbolic.codegen.staged_c.\n{rings} */\n"
        f'#include "{name}.h"\n\n{signature}\n{{\n    (void)mem;\n' + "\n".join(body)
        + "\n    return 0;\n}\n")
    return files, sizes
