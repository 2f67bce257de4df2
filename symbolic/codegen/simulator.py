"""The compiled simulators' C: each loop's functions and its driver.

:func:`simulator_sources` writes one part of a loop's simulator (see
:data:`SIMULATOR_PARTS`): each function of the :class:`quadland_symbolic.loop.LoopModel`
as CasADi writes it, one translation unit each, and the driver
(``symbolic/templates/simulator.c.jinja``), which knows nothing of the model
but its functions' sizes. The sampled driver's plant, free plant and event are each
cut in two where their terms of the time and the parameters alone are worth it
(:data:`HOISTING`, :func:`~quadland_symbolic.codegen.time_split.time_split`): those
terms in ``<function>_time``, which the driver calls once an instant, the same bits.
Each function's C reads its arguments and writes its results through pointers taken once a
call (:func:`direct_access`), the same bits. :func:`loop_header` writes the loop algorithm
the drivers and the pure-C examples share (``quadland_loop.h``).
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import casadi as ca

from quadland_symbolic.codegen.staged_c import staged_sources
from quadland_symbolic.codegen.time_split import time_split
from quadland_symbolic.loop import MAX_DELAY_PERIODS, RIDE_TOL, LoopModel

__all__ = ["SIMULATOR_PARTS", "loop_header", "simulator_sources"]

#: The parts of a compiled simulator: each one's driver and the functions it calls.
#: ``"sampled_flight"`` flies the flight code (``quadland.h``'s
#: ``ql_control_step``; ``quadland_landing.h``'s ``ql_guidance_step`` and
#: ``ql_landing_step``; on sensors also ``quadland_estimator.h``'s and
#: ``quadland_land_detector.h``'s steps) in place of the symbolic controller,
#: through the model's adapter (:attr:`LoopModel.flight`); its build adds the
#: flight sources.
SIMULATOR_PARTS = {"continuous": ("continuous", ("rhs", "outputs", "envelope")),
                   "sampled": ("sampled", ("plant", "controller", "assemble", "outputs",
                                           "envelope")),
                   "sampled_flight": ("sampled", ("plant", "step_args", "assemble", "outputs",
                                                  "envelope"))}


def loop_header(precision: str | None = None) -> str:
    """``quadland_loop.h``: the loop algorithm the simulators and the pure-C examples share.

    Clocks and their merged grid, RK4 over a span, the event's bisection
    (``symbolic/templates/quadland_loop.h.jinja``); ``quadland.engine.loop``
    mirrors it in Python.
    """
    from quadland_symbolic.codegen.render import common_context, render  # Jinja2: on use

    return render("quadland_loop.h.jinja", **dict(common_context(None), precision=precision,
                                                   ride_tol=repr(RIDE_TOL)))


def simulator_sources(model: LoopModel, part: str) -> dict[str, str]:
    """C sources of one part of a compiled simulator of ``model``, by file name.

    Parameters
    ----------
    model : LoopModel
    part : {"continuous", "sampled"}
        Which loop; see :data:`SIMULATOR_PARTS`.

    Returns
    -------
    dict of str to str
        ``<prefix><function>.c/.h``: each function the part calls, as
        CasADi writes it, named ``<prefix><function>`` (one translation unit
        each, so that a build compiles them in parallel); ``<prefix><part>.c``:
        the driver (``symbolic/templates/simulator.c.jinja``): RK4 over an
        exact grid, one call per run, parameters passed once and shared,
        outputs written straight into the caller's arrays. ``prefix`` is
        ``qlsim_<model name>_``. The text depends only on the model and the
        CasADi version.
    """
    from quadland_symbolic.codegen.render import render  # Jinja2: on use

    if part not in SIMULATOR_PARTS:
        raise ValueError(f"part must be one of {', '.join(SIMULATOR_PARTS)}, got {part!r}")
    prefix = f"qlsim_{model.name}_"
    by_name = {f.name(): f for f in model.functions()}
    driver, names = SIMULATOR_PARTS[part]
    if driver == "sampled" and model.event is not None:
        names = (*names, "event")
    has_free = driver == "sampled" and model.free_plant is not None and model.event_continues
    if has_free:
        names = (*names, "free_plant")
    has_ride = driver == "sampled" and model.ride_rhs is not None
    if has_ride:
        names = (*names, "ride_rhs", "ride_row")
    if model.envelope is None:
        names = tuple(n for n in names if n != "envelope")
    files, work, rings, hoisted, params = {}, [], (), {}, (0, 0, False)
    for name in names:
        if name == "controller" and model.controller_stages is not None:
            rings, params = _staged(model, prefix, driver, files, work, has_free)
            continue
        split = _split(by_name[name]) if driver == "sampled" and name in HOISTING else None
        for f in (by_name[name],) if split is None else split:
            work.append(_emit_sized(prefix, f, files))
        if split is not None:
            hoisted[name] = split[1].nnz_out(0)
    sizes = dict(NX=model.state.size, NW=model.disturbance.size, NP=model.params.size,
                 NY=model.outputs.size, NXP=model.plant_state.size, NUH=model.held.size,
                 NXC=model.controller_state.size, NPP=model.plant_params.size,
                 NPC=model.controller_params.size, NREC=model.recorded.size,
                 NENV=model.envelope_layout.size if model.envelope is not None else 0,
                 NZ=model.ride_rhs.nnz_in(0) if has_ride else 0,
                 NA=model.ride_row.nnz_in(1) if has_ride else 0,
                 NN=model.tick_inputs.size if model.tick_inputs is not None else 0)
    headers = [n for n in names if n != "step_args"] + (
        ["controller"] if part == "sampled_flight" else []) + [f"{n}_time" for n in hoisted]
    files["quadland_loop.h"] = loop_header()
    files[f"{prefix}{part}.c"] = render("simulator.c.jinja",
        prefix=prefix, model=model.name, part=driver, name=part, functions=headers,
        has_event=driver == "sampled" and model.event is not None,
        event_continues=driver == "sampled" and model.event is not None
        and model.event_continues,
        has_envelope=model.envelope is not None, max_delay=MAX_DELAY_PERIODS,
        has_ride=has_ride, has_free=has_free,
        has_tick=driver == "sampled" and model.tick_inputs is not None, rings=rings,
        hoisted=hoisted, controller_params=params[0], controller_inputs=params[1],
        controller_free=params[2],
        ring_slots=max((r["n"] for r in rings), default=0) + 1,
        core=_core(model.controller_state.size, rings),
        casadi_version=ca.__version__, sizes=sizes,
        **{k: max(w[k] for w in work) for k in ("sz_arg", "sz_res", "sz_iw", "sz_w")})
    if part == "sampled_flight":
        files.update(_flight_controller(model, prefix, by_name["step_args"]))
    return files


#: The sampled driver's arguments of the controller constant over a flight: its
#: parameters (``k.arg[2]``, and ``k.arg[7]`` where the controller reads tick inputs).
CONSTANT_ARGS = {2: "pc", 7: "pp"}


def _staged(model: LoopModel, prefix: str, driver: str, files: dict, work: list,
            has_free: bool = False):
    """The staged controller's C added to ``files``, its work sizes to ``work``; its rings
    (:func:`_rings`) and ``(values of its parameters alone, inputs, whether it reads the
    driver's flag of the gear far from the deck)``: with ``has_free`` (the driver flies
    the free plant), its stages' free functions where the driver does."""
    inputs = model.controller_stages.inputs
    staged, sz = staged_sources(prefix, model.controller_stages, lambda n, f: _emit(n, f)[0],
                                _constants(inputs, driver, model.tick_inputs), has_free)
    files.update(staged)
    work.append({k: v for k, v in sz.items() if k != "free"})
    return _rings(model.controller_stages), (sz["n_params"], len(inputs), sz["free"])


def _constants(inputs, driver: str, tick_inputs) -> tuple[str, ...]:
    """The staged controller's inputs the sampled driver holds constant over a flight
    (:data:`CONSTANT_ARGS`, where they are the inputs of those names); none in another
    driver."""
    if driver != "sampled":
        return ()
    return tuple(n for i, n in CONSTANT_ARGS.items()
                 if i < len(inputs) and inputs[i][0] == n and (i == 2 or tick_inputs is not None))


#: The sampled driver's functions of the plant's state at an instant whose terms of the
#: time and the parameters alone are computed once an instant (:func:`time_split`).
HOISTING = ("plant", "free_plant", "event")
#: The fewest instructions of those terms worth a function of their own: below, the
#: driver's check of the instant and the call cost about what they save.
MIN_HOISTED = 32


def _split(f: ca.Function):
    """``(core, <name>_time)`` of ``f`` by :func:`time_split`, or ``None`` where its terms
    of time alone are fewer than :data:`MIN_HOISTED` instructions."""
    split = time_split(f, ("t", "pp"))
    if split is None or split[1].n_instructions() < MIN_HOISTED:
        return None
    return split


def _rings(staged) -> tuple[dict, ...]:
    """The controller's delay lines the driver keeps as rings
    (:attr:`quadland_symbolic.stages.Staged.rings`): each one's ``res`` (the pointer
    the controller's C takes it at), ``offset`` in the controller's memory (its input
    ``xc`` and output ``xc_next``), slots of ``m`` values, ``n`` of them; ``at``:
    where its slots begin in the driver's array of rings."""
    places = staged.ring_places()
    slots = max((n for *_, n in places), default=0) + 1     # the driver's RING_SLOTS
    out, at = [], 0
    for i, (src, dst, start, m, n) in enumerate(places):
        if (staged.inputs[src][0], dst) != ("xc", 0):
            raise ValueError(f"ring {staged.rings[i][0]}: not a line of the controller's "
                             "memory (xc, xc_next)")
        out.append(dict(res=len(staged.outputs) + i, offset=start, m=m, n=n, at=at))
        at += 2 * slots * m
    return tuple(out)


def _core(nxc: int, rings) -> tuple[tuple[int, int], ...]:
    """The ranges ``(start, stop)`` of the controller's memory outside its rings."""
    out, at = [], 0
    for r in sorted(rings, key=lambda r: r["offset"]):
        if r["offset"] > at:
            out.append((at, r["offset"]))
        at = r["offset"] + r["m"] * r["n"]
    if at < nxc:
        out.append((at, nxc))
    return tuple(out)


def _emit_sized(prefix: str, f: ca.Function, files: dict) -> dict:
    """``f``'s C (:func:`_emit`, named ``<prefix><its name>``) added to ``files``; its
    work sizes."""
    text, fn = _emit(prefix + f.name(), f)
    files.update(text)
    return dict(sz_arg=fn.sz_arg(), sz_res=fn.sz_res(), sz_iw=fn.sz_iw(), sz_w=fn.sz_w())


def _emit(name: str, f: ca.Function) -> tuple[dict[str, str], ca.Function]:
    """CasADi's ``<name>.c/.h`` of ``f`` renamed ``name`` (its helpers prefixed ``name_``),
    and the renamed Function."""
    args = f.sx_in() if f.is_a("SXFunction") else f.mx_in()     # MX: its branches kept
    fn = ca.Function(name, args, f.call(args), f.name_in(), f.name_out())
    cg = ca.CodeGenerator(f"{name}.c", {"with_header": True, "with_export": False,
                                        "prefix": f"{name}_", "verbose": False})
    cg.add(fn)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        text = {f"{name}.{ext}": Path(tmp, f"{name}.{ext}").read_text() for ext in ("c", "h")}
    if INLINE_MIN_MAX:
        text[f"{name}.c"] = inline_min_max(text[f"{name}.c"])
    if DIRECT_ACCESS:
        text[f"{name}.c"] = direct_access(text[f"{name}.c"])
    return text, fn


#: Whether the simulators' ``casadi_fmin``/``casadi_fmax`` compare inline
#: (:func:`inline_min_max`) rather than call libm. The cache's keys hash this module's
#: text, not the value: a build with it turned off at run time (the benchmark's) needs a
#: model of another name.
INLINE_MIN_MAX = True
#: CasADi's calls of C99's ``fmax``/``fmin`` in its ``casadi_fmax``/``casadi_fmin``, and
#: the same value computed inline on x86-64 with glibc.
_MIN_MAX = {
    "  return fmax(x, y);\n":
        "#if defined(__x86_64__) && defined(__GLIBC__)\n"
        "  if (!isnan(x) && !isnan(y)) return x > y ? x : y;\n#endif\n  return fmax(x, y);\n",
    "  return fmin(x, y);\n":
        "#if defined(__x86_64__) && defined(__GLIBC__)\n"
        "  if (!isnan(x) && !isnan(y)) return x < y ? x : y;\n#endif\n  return fmin(x, y);\n"}


def inline_min_max(c: str) -> str:
    """CasADi's C with its ``casadi_fmax(x, y)`` and ``casadi_fmin(x, y)`` computed inline
    where libm is glibc's on x86-64, whose ``fmax`` is ``maxsd`` (``x > y ? x : y``: ``y``
    for equal operands, ``+0.0`` and ``-0.0`` included) and ``fmin`` ``minsd`` (``x < y ?
    x : y``) when neither is a NaN; with a NaN, and elsewhere, libm's call as before.

    This is glibc's x86-64 assembly (``sysdeps/x86_64/fpu/s_fmax.S``, ``s_fmin.S``), not
    its generic C, which returns ``x`` for equal operands: a glibc that moved to the
    generic form would give the other zero of ``fmax(+0.0, -0.0)``.
    ``tests/test_inline_min_max.py`` compares the inline form with the machine's own
    ``fmax`` and ``fmin`` on every pair of special values, so such a libm fails it."""
    for call, inline in _MIN_MAX.items():
        c = c.replace(call, inline)
    return c


#: Whether the simulators' SX bodies read and write through pointers taken once a call
#: (:func:`direct_access`). The cache's keys hash this module's text, not the value: a
#: build with it turned off at run time (the benchmark's) needs a model of another name.
DIRECT_ACCESS = True
#: Largest result CasADi's body writes (its last index + 1) that :func:`direct_access`
#: gives a sink on the stack for: 8,192 doubles (64 KiB); a body with a larger one keeps
#: its writes as CasADi writes them.
DIRECT_SINK_MAX = 8192
#: An SX body as CasADi 3.x writes it: ``static int casadi_fN(...) {`` to the first
#: ``}`` at the start of a line.
_BODY = re.compile(r"^static int casadi_f\d+\(const casadi_real\*\* arg, casadi_real\*\* res, "
                   r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n", re.M)
#: An SX body's read of element ``j`` of argument ``i`` (zero where ``arg[i]`` is null),
#: and its write of element ``j`` of result ``i`` (none where ``res[i]`` is null).
_READ = re.compile(r"=arg\[(\d+)\]\? arg\[\1\]\[(\d+)\] : 0;")
_WRITE = re.compile(r"^  if \(res\[(\d+)\]!=0\) res\[\1\]\[(\d+)\]=", re.M)


def _extent(matches) -> dict[int, int]:
    """Each argument's or result's index ``i``: its last element read or written + 1."""
    out: dict[int, int] = {}
    for m in matches:
        out[int(m[1])] = max(out.get(int(m[1]), 0), int(m[2]) + 1)
    return out


def direct_access(c: str) -> str:
    """CasADi's C with each SX body's reads and writes through pointers taken once a call.

    CasADi writes an SX function's every read of an argument as ``a=arg[i]? arg[i][j] :
    0;`` and every write of a result as ``if (res[i]!=0) res[i][j]=a;``: a test and a
    branch on the pointer at each of the thousands of elements of a stage (the pointers
    cannot change during the call; GCC does not merge the tests). Here each body takes
    ``ql_a<i> = arg[i] ? arg[i] : ql_z`` once (``ql_z`` a static array of zeros as long
    as the longest argument read) and ``ql_r<i> = res[i] ? res[i] : ql_s`` (``ql_s`` a
    sink on the stack, as long as the longest result written), and reads ``ql_a<i>[j]``
    and writes ``ql_r<i>[j]``. A read gives what it gave (the element, or ``+0.0`` where
    the argument is null: ``0`` converted, as the zeros are); a write goes where it went,
    or to the sink, which nothing reads, where it went nowhere; every operation is the
    one it was: the same bits. 7 % fewer instructions a ``highway`` flight
    (docs/performance.md, "twentieth"). MX bodies (their own forms, with spaces) and a
    body whose result is over :data:`DIRECT_SINK_MAX` keep their writes as they are.
    ``tests/test_direct_access.py`` compares the two forms bit for bit, null pointers
    included."""
    out, at = [], 0
    for head in _BODY.finditer(c):
        end = c.index("\n}\n", head.end())
        body = c[head.end():end]
        reads = _extent(_READ.finditer(body))
        writes = _extent(_WRITE.finditer(body))
        if writes and max(writes.values()) > DIRECT_SINK_MAX:
            writes = {}
        if not reads and not writes:
            continue
        decl = []
        if reads:
            decl.append(f"  static const casadi_real ql_z[{max(reads.values())}] = {{0}};")
            decl += [f"  const casadi_real* const ql_a{i} = arg[{i}] ? arg[{i}] : ql_z;"
                     for i in sorted(reads)]
            body = _READ.sub(lambda m: f"=ql_a{m[1]}[{m[2]}];", body)
        if writes:
            decl.append(f"  casadi_real ql_s[{max(writes.values())}];")
            decl += [f"  casadi_real* const ql_r{i} = res[{i}] ? res[{i}] : ql_s;"
                     for i in sorted(writes)]
            body = _WRITE.sub(lambda m: f"  ql_r{m[1]}[{m[2]}]=", body)
        out += [c[at:head.end()], "\n".join(decl), "\n", body]
        at = end
    out.append(c[at:])
    return "".join(out)


def _flight_controller(model: LoopModel, prefix: str, args: ca.Function) -> dict[str, str]:
    """``<prefix>controller.c/.h``: the model's flight step behind the controller's signature.

    ``args`` is the model's ``step_args`` Function (the step's arguments
    from the loop's state); the C is the model's ``flight`` template.
    """
    from quadland_symbolic.codegen.render import render  # Jinja2: on use

    if model.flight is None:
        raise ValueError(f"the loop {model.name!r} has no flight code")
    offsets = {lay.name: lay.offsets() for lay in (model.controller_state, model.recorded)}
    nested = {f.name: {g.name: a for g, (a, _) in zip(
        f.layout.fields, f.layout.offsets().values(), strict=True)}
        for f in model.controller_state.fields if f.layout is not None}
    files = {}
    files[f"{prefix}controller.h"] = (
        f"/* {prefix}controller: the flight step behind the controller's signature. */\n"
        f"#include \"{prefix}step_args.h\"\n"
        f"int {prefix}controller(const casadi_real** arg, casadi_real** res, "
        "casadi_int* iw, casadi_real* w, int mem);\n")
    files[f"{prefix}controller.c"] = render(model.flight,
        prefix=prefix, model=model.name, casadi_version=ca.__version__,
        args=[(n, args.nnz_out(i)) for i, n in enumerate(args.name_out())],
        sz_iw=args.sz_iw(), sz_w=args.sz_w(),
        xc=[(f.name, offsets[model.controller_state.name][f.name][0])
            for f in model.controller_state.fields],
        rec=[(f.name, offsets[model.recorded.name][f.name][0])
             for f in model.recorded.fields],
        rec_elements=list(model.recorded.element_names()),
        nested=nested)
    return files
