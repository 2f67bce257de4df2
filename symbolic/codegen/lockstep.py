"""C that evaluates W instances of an SX Function in lockstep (SIMD across runs).

A campaign flies many independent landings of one loop; their flight code is the same
branch-free arithmetic on different values. :func:`lockstep_c` writes a Function's
algorithm (CasADi's SX instructions, :meth:`casadi.Function.instruction_id` and its
operands) as C in which every work value is a GCC vector of ``width`` doubles, one lane
per instance: the additions, products, comparisons and selections become vector
instructions, ``fmin`` and ``fmax`` are written with vector masks as glibc computes
them, and libm's other functions (sines, square roots, ``pow`` ...) are called lane by
lane. Each lane computes exactly what CasADi's own C computes for one instance, the
same operations in the same order, so with the compiler's default floating-point
semantics (no ``-ffast-math``; ``-ffp-contract=off`` so that no product and sum fuse)
the results are the scalar function's bit for bit (``tests/test_lockstep.py``), but
for the sign of ``fmin``/``fmax`` of +0.0 and -0.0, which C leaves unspecified.

A prototype for issue 20 (item 2, "vectorizing across runs"), measured in
``benchmarks/bench_lockstep.py`` and ``docs/performance.md`` ("Lockstep across runs");
nothing in the runtime calls it.
"""

from __future__ import annotations

import re

import casadi as ca

from quadland_symbolic.codegen.render import common_context, render

__all__ = ["LANE_OPS", "MINMAX_OPS", "VECTOR_OPS", "lockstep_c", "lockstep_supported"]

#: Operations written as vector expressions of the operands ``{x}`` and ``{y}`` (work
#: vectors): CasADi's C for one instance (``(a0<a1)``, ``(a0?a1:0)``, ``(!a0)``,
#: ``casadi_fabs``) gives 1.0 or +0.0 for a truth value and the operand or +0.0 for a
#: selection; the masks (``one_``: the bits of 1.0, ``abs_``: all but the sign) give
#: the same bits lane by lane.
VECTOR_OPS: dict[int, str] = {
    ca.OP_ASSIGN: "{x}",
    ca.OP_ADD: "{x} + {y}",
    ca.OP_SUB: "{x} - {y}",
    ca.OP_MUL: "{x} * {y}",
    ca.OP_DIV: "{x} / {y}",
    ca.OP_NEG: "-{x}",
    ca.OP_SQ: "{x} * {x}",
    ca.OP_TWICE: "2.0 * {x}",
    ca.OP_INV: "1.0 / {x}",
    ca.OP_LT: "({v})(({m})({x} < {y}) & one_)",
    ca.OP_LE: "({v})(({m})({x} <= {y}) & one_)",
    ca.OP_EQ: "({v})(({m})({x} == {y}) & one_)",
    ca.OP_NE: "({v})(({m})({x} != {y}) & one_)",
    ca.OP_NOT: "({v})(({m})({x} == zero_) & one_)",
    ca.OP_AND: "({v})(({m})({x} != zero_) & ({m})({y} != zero_) & one_)",
    ca.OP_OR: "({v})((({m})({x} != zero_) | ({m})({y} != zero_)) & one_)",
    ca.OP_IF_ELSE_ZERO: "({v})(({m})({x} != zero_) & ({m}){y})",
    ca.OP_FABS: "({v})(({m}){x} & abs_)",
}

#: ``fmin`` and ``fmax`` as vector statements (``{o}``: the result): what glibc's x86-64
#: ``fmin``/``fmax`` return (``sysdeps/x86_64/fpu/s_fmax.S``: ``minsd``/``maxsd``, so
#: ``x`` when it is below (above) ``y``, else ``y``, ties of zeros included; the number
#: when one operand is NaN; ``x + y`` when both are). C leaves the tie of +0.0 and -0.0
#: unspecified, and a compiler may swap the operands of the scalar call (gcc does).
MINMAX_OPS: dict[int, str] = {
    op: ("{{ const {m} c_ = ({m})({x} " + cmp + " {y}), ny_ = ({m})({y} != {y}), "
         "nn_ = ny_ & ({m})({x} != {x}); "
         "{m} r_ = (c_ & ({m}){x}) | (~c_ & ({m}){y}); "
         "r_ = (ny_ & ({m}){x}) | (~ny_ & r_); "
         "{o} = ({v})((nn_ & ({m})({x} + {y})) | (~nn_ & r_)); }}")
    for op, cmp in ((ca.OP_FMIN, "<"), (ca.OP_FMAX, ">"))}

#: Operations evaluated lane by lane (``{x}``, ``{y}``: one lane of the operands), as
#: CasADi's C writes them for one instance (C99 libm; ``casadi_sign``'s expression).
LANE_OPS: dict[int, str] = {
    **{getattr(ca, f"OP_{name.upper()}"): f"{name}({{x}})"
       for name in ("sqrt", "exp", "log", "sin", "cos", "tan", "asin", "acos", "atan",
                    "sinh", "cosh", "tanh", "floor", "ceil", "erf", "expm1", "log1p")},
    **{getattr(ca, f"OP_{name.upper()}"): f"{name}({{x}}, {{y}})"
       for name in ("atan2", "pow", "fmod", "copysign", "hypot")},
    ca.OP_CONSTPOW: "pow({x}, {y})",
    ca.OP_SIGN: "{x} < 0 ? -1.0 : {x} > 0 ? 1.0 : {x}",
}

_BINARY = {ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_DIV, ca.OP_LT, ca.OP_LE, ca.OP_EQ,
           ca.OP_NE, ca.OP_AND, ca.OP_OR, ca.OP_IF_ELSE_ZERO, ca.OP_ATAN2, ca.OP_POW,
           ca.OP_CONSTPOW, ca.OP_FMIN, ca.OP_FMAX, ca.OP_FMOD, ca.OP_COPYSIGN, ca.OP_HYPOT}

_OP_NAMES = {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")}


def lockstep_supported(fn: ca.Function) -> list[str]:
    """The operations of ``fn`` that :func:`lockstep_c` cannot write, by CasADi name.

    Parameters
    ----------
    fn : casadi.Function
        An SX Function.

    Returns
    -------
    list of str
        Sorted names (``"OP_CALL"``, ...); empty when every instruction is written.
    """
    known = {ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST, *VECTOR_OPS, *MINMAX_OPS, *LANE_OPS}
    return sorted({_OP_NAMES.get(op, str(op)) for op in map(fn.instruction_id,
                                                             range(fn.n_instructions()))
                   if op not in known})


def _literal(c: float) -> str:
    """``c`` as an exact C99 literal (hexadecimal; infinities by ``INFINITY``)."""
    if c != c:
        raise ValueError("a NaN constant has no portable exact literal")
    if c in (float("inf"), float("-inf")):
        return "INFINITY" if c > 0 else "-INFINITY"
    return c.hex()


def _statement(fn: ca.Function, k: int, width: int, vec: str, mask: str) -> str:
    """Instruction ``k`` of ``fn`` as one C statement on the work vectors ``w<i>``."""
    op, out, ins = fn.instruction_id(k), fn.instruction_output(k), fn.instruction_input(k)
    if op == ca.OP_INPUT:
        return f"memcpy(&w{out[0]}, in{ins[0]}_ + {width * ins[1]}, sizeof w{out[0]});"
    if op == ca.OP_OUTPUT:
        return f"memcpy(out{out[0]}_ + {width * out[1]}, &w{ins[0]}, sizeof w{ins[0]});"
    if op == ca.OP_CONST:
        c = _literal(fn.instruction_constant(k))
        return f"w{out[0]} = ({vec}){{{', '.join([c] * width)}}};"
    x, y = f"w{ins[0]}", f"w{ins[1]}" if op in _BINARY else ""
    if op in VECTOR_OPS:
        return f"w{out[0]} = " + VECTOR_OPS[op].format(x=x, y=y, v=vec, m=mask) + ";"
    if op in MINMAX_OPS:
        return MINMAX_OPS[op].format(x=x, y=y, o=f"w{out[0]}", v=vec, m=mask)
    if op in LANE_OPS:
        lane = LANE_OPS[op].format(x=f"{x}[l_]", y=f"{y}[l_]")
        return f"for (l_ = 0; l_ < {width}; ++l_) w{out[0]}[l_] = {lane};"
    raise ValueError(f"lockstep_c: {fn.name()} uses {_OP_NAMES.get(op, op)}, which it "
                     "cannot write")


def _sincos_pairs(fn: ca.Function) -> dict[int, int]:
    """Each sine (cosine) instruction whose argument's cosine (sine) follows, before the
    argument is written again: ``{first: second}``."""
    pending: dict[int, tuple[int, int]] = {}
    pairs = {}
    for k in range(fn.n_instructions()):
        op = fn.instruction_id(k)
        if op in (ca.OP_SIN, ca.OP_COS):
            v = fn.instruction_input(k)[0]
            first = pending.pop(v, None)
            if first is not None and first[1] != op:
                pairs[first[0]] = k
            else:
                pending[v] = (k, op)
        if op != ca.OP_OUTPUT:
            pending.pop(fn.instruction_output(k)[0], None)
    return pairs


def _paired(fn: ca.Function, k: int, partner: int, width: int) -> str:
    """Instruction ``k``, a sine or cosine, and its partner's value into ``t<k>`` in one
    lane loop, where the compiler calls ``sincos`` once as in the scalar C."""
    names = {ca.OP_SIN: "sin", ca.OP_COS: "cos"}
    x, out = fn.instruction_input(k)[0], fn.instruction_output(k)[0]
    return (f"for (l_ = 0; l_ < {width}; ++l_) {{ const double x_ = w{x}[l_]; "
            f"w{out}[l_] = {names[fn.instruction_id(k)]}(x_); "
            f"t{k}[l_] = {names[fn.instruction_id(partner)]}(x_); }}")


def _body(fn: ca.Function, width: int, vec: str, mask: str) -> tuple[list[str], list[str]]:
    """The statements of ``fn``'s algorithm and the vectors they use."""
    body, used, written = [], set(), set()
    pairs = _sincos_pairs(fn)
    second = {k2: k1 for k1, k2 in pairs.items()}
    for k in range(fn.n_instructions()):
        if k in pairs:
            body.append(_paired(fn, k, pairs[k], width))
        elif k in second:
            body.append(f"w{fn.instruction_output(k)[0]} = t{second[k]};")
        else:
            body.append(_statement(fn, k, width, vec, mask))
        op = fn.instruction_id(k)
        if op == ca.OP_OUTPUT:
            written.add(tuple(fn.instruction_output(k)))
        else:
            used.add(fn.instruction_output(k)[0])
    missing = [(i, nz) for i in range(fn.n_out()) for nz in range(fn.nnz_out(i))
               if (i, nz) not in written]
    if missing:
        raise ValueError(f"lockstep_c: {fn.name()} leaves output nonzeros unwritten "
                         f"(first: output {missing[0][0]}, nonzero {missing[0][1]})")
    return body, [f"w{i}" for i in sorted(used)] + [f"t{k}" for k in sorted(pairs)]


def lockstep_c(fn: ca.Function, width: int, name: str | None = None,
               source: str | None = None) -> str:
    """C of ``fn`` evaluating ``width`` instances in lockstep, one per vector lane.

    Parameters
    ----------
    fn : casadi.Function
        An SX Function in double precision; every output nonzero must be computed
        (each has an output instruction, as in every SX Function CasADi builds).
    width : int
        Instances per call, W (1 to 16, a power of two: a GCC vector's lanes).
    name : str, optional
        The C function's name; ``<fn.name()>_lockstep<W>`` by default.
    source : str, optional
        What built ``fn``, for the file's banner; ``fn``'s name by default.

    Returns
    -------
    str
        One translation unit defining ``void name(const double* const* arg,
        double* const* res)``: ``arg[i]`` holds input ``i`` of the W instances value by
        value (nonzero ``k`` of instance ``j`` at ``arg[i][W * k + j]``), ``res[i]``
        likewise. Compile it with GCC or Clang (vector extensions), without
        ``-ffast-math``, with ``-ffp-contract=off`` (or ``-std=c99``, which implies it).

    Raises
    ------
    ValueError
        When ``fn`` is not an SX Function, ``width`` is not a power of two from 1 to 16,
        an operation has no lockstep form (:func:`lockstep_supported`), a constant is
        NaN, or an output nonzero is not written.

    Notes
    -----
    The statements are CasADi's algorithm in its order, each work value a vector
    variable ``w<i>`` (CasADi reuses its work values, so there are about as many
    vectors as the scalar C has scalars). The pointers ``arg[i]`` and ``res[i]`` are
    read once into locals: ``memcpy`` may write any object, and the compiler would
    otherwise read them again after every output written (2,200 more instructions in
    the navigation filter's step). Lane ``j`` of a vector operation is the
    scalar operation on lane ``j``'s operands, which IEEE 754 defines bit for bit; the
    truth values are built from comparison masks and the bits of 1.0, and the
    selections from masks and the selected operand's bits, which is what the scalar
    C's ``(c?x:0)`` and ``(a<b)`` give (``+0.0`` when false); ``fmin`` and ``fmax``
    are :data:`MINMAX_OPS`, libm's other functions are called lane by lane. A sine and
    a cosine of one value are computed in one lane loop (the second kept in a vector
    ``t<k>`` until its turn), where the compiler calls ``sincos`` once, as it does in
    the scalar C (the same bits: glibc's ``sincos`` is its ``sin`` and ``cos``).

    Examples
    --------
    >>> x = ca.SX.sym("x", 2)
    >>> text = lockstep_c(ca.Function("f", [x], [ca.sin(x[0]) * x[1]]), 4)
    >>> "void f_lockstep4(const double* const* arg, double* const* res)" in text
    True
    """
    if not fn.is_a("SXFunction"):
        raise ValueError(f"lockstep_c: {fn.name()} is not an SX Function")
    if width not in (1, 2, 4, 8, 16):
        raise ValueError(f"lockstep_c: width must be 1, 2, 4, 8 or 16, got {width}")
    name = name or f"{fn.name()}_lockstep{width}"
    if not re.fullmatch(r"[A-Za-z_]\w*", name):
        raise ValueError(f"lockstep_c: {name!r} is not a C name")
    vec, mask = f"{name}_v", f"{name}_m"
    body, names = _body(fn, width, vec, mask)
    work = [", ".join(names[i:i + 12]) for i in range(0, len(names), 12)]
    what = re.sub(r"\s+", " ", str(fn)).removesuffix(" SXFunction")
    return render("lockstep.c.jinja", name=name, width=width, vec=vec, mask=mask,
                  work=work, body=body, n_in=fn.n_in(), n_out=fn.n_out(),
                  what=f"{name}: {what}", source=source or fn.name(), **common_context(None))
