"""CasADi's generated C, post-processed: prefixed, compiling alone, float-clean."""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import casadi as ca

from quadland_symbolic.codegen.config import CodegenConfig
from quadland_symbolic.codegen.registry import GeneratedFunction
from quadland_symbolic.codegen.render import common_context, render

__all__ = ["emit_casadi"]

_MATH = ("exp", "expm1", "log", "log1p", "sqrt", "cos", "sin", "tan", "acos", "asin", "atan",
         "atan2", "tanh", "sinh", "cosh", "fmin", "fmax", "fabs", "floor", "ceil", "pow", "erf",
         "hypot")


_MATH_RE = re.compile(r"\b(" + "|".join(_MATH) + r")\(")


_LITERAL_RE = re.compile(r"(?<![\w.])(\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")


def emit_casadi(entry: GeneratedFunction, l: int, config: CodegenConfig) -> dict[str, str]:
    """CasADi's C for one function, prefixed and post-processed; ``{file name: text}``."""
    fn = entry.function(l)
    c_name = entry.c_name(config)
    # The same expression graph under the build's symbol (CasADi names the C
    # function after the Function); "prefix" names its helpers c_name__*.
    # An MX Function (its branches kept: quadland_symbolic.landing.estimator_switch) by MX.
    ins = fn.sx_in() if fn.is_a("SXFunction") else fn.mx_in()
    renamed = ca.Function(c_name, ins, fn.call(ins), fn.name_in(), fn.name_out())
    opts = {"with_header": True, "casadi_real": config.precision, "casadi_int": config.casadi_int,
            "prefix": f"{c_name}_", "verbose": False, "with_export": False}
    cg = ca.CodeGenerator(f"{entry.name}.c", opts)
    cg.add(renamed)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        texts = {ext: Path(tmp, f"{entry.name}.{ext}").read_text() for ext in ("c", "h")}
    c = texts["c"]
    # Arguments CasADi's SX code leaves unused (-Wunused-parameter).
    c = re.sub(r"(static int \w+\(const casadi_real\*\* arg, casadi_real\*\* res, "
               r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n)",
               r"\1  (void)arg; (void)res; (void)iw; (void)w; (void)mem;\n", c)
    c = re.sub(r"(void \w+_release\(int mem\) \{\n)", r"\1  (void)mem;\n", c)
    c = re.sub(r"(casadi_real \w+_default_in\(casadi_int i\) \{\n)", r"\1  (void)i;\n", c)
    h = texts["h"]
    if not config.null_checks:
        c = re.sub(r"arg\[(\d+)\]\? arg\[\1\]\[(\d+)\] : 0", r"arg[\1][\2]", c)
        c = re.sub(r"if \(res\[(\d+)\]!=0\) res\[\1\]", r"res[\1]", c)
        c = c.replace(f"int {c_name}(const casadi_real** arg,",
                      "/* Every arg[i] and res[i] must point to valid memory: NULL is not\n"
                      " * accepted (quadland_symbolic.codegen.CodegenConfig.null_checks). */\n"
                      f"int {c_name}(const casadi_real** arg,", 1)
        h = h.replace(f"int {c_name}(const casadi_real** arg,",
                      "/* Every arg[i] and res[i] must point to valid memory. */\n"
                      f"int {c_name}(const casadi_real** arg,", 1)
    if config.is_float:
        head, sep, body = c.partition("#include <math.h>")
        body = _MATH_RE.sub(lambda m: config.math(m.group(1)) + "(", body)
        body = _LITERAL_RE.sub(lambda m: m.group(1) + "f", body)
        c = head + sep + body
    what = re.sub(r"\s+", " ", str(fn)).removesuffix(" SXFunction")
    ctx = dict(common_context(config), what=f"{c_name}: {what}", source=entry.origin(l))
    return {f"{entry.name}.{ext}": render("casadi.jinja", code=text, **ctx)
            for ext, text in (("c", c), ("h", h))}

