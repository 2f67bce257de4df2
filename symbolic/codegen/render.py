"""The one Jinja2 environment of the generated C, and the context every template shares."""

from __future__ import annotations

import functools
import re

import casadi as ca
import jinja2

from quadland_symbolic.codegen.config import TEMPLATE_DIR, CodegenConfig

__all__ = ["pad", "signature", "declared", "fail", "environment", "render", "common_context"]


def pad(text: str, width: int) -> str:
    return text.ljust(width)


def signature(params, head: str, width: int = 96) -> str:
    """``head(p1, p2, ...)`` wrapped before ``width``, continuation under the ``(``."""
    indent = " " * (len(head) + 1)
    lines, line = [], head + "("
    for i, p in enumerate(params):
        piece = p + (", " if i < len(params) - 1 else ")")
        if len(line) + len(piece.rstrip()) > width and line.strip() != head + "(":
            lines.append(line.rstrip())
            line = indent
        line += piece
    lines.append(line)
    return "\n".join(lines)


@functools.cache
def declared(text: str, ql: str, QL: str) -> list[str]:
    """The names a rendered header declares with the build's prefixes, sorted."""
    return sorted(set(re.findall(rf"\b(?:{ql}|{QL})\w+", text)))


def fail(message: str):
    """Stop a rendering with ``message`` (a template meets what it cannot write)."""
    raise ValueError(message)


@functools.cache
def environment() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATE_DIR)),
                             keep_trailing_newline=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, autoescape=False)
    env.filters.update(pad=pad, signature=signature, declared=declared,
                       prefix=lambda text, head: head + text)
    env.globals["fail"] = fail
    return env


def render(template: str, **context) -> str:
    return environment().get_template(template).render(**context)


def common_context(config: CodegenConfig | None) -> dict:
    """Context every template shares: the banner's facts and the prefixes."""
    ctx = dict(builder=(config or CodegenConfig()).builder, casadi_version=ca.__version__,
               precision=config.precision if config else None)
    if config is not None:
        ql, QL = config.prefix, config.macro_prefix
        ctx.update(ql=ql, QL=QL, real=ql + "real", lit=config.literal, math=config.math,
                   api=lambda text: text.replace("{ql}", ql).replace("{QL}", QL))
    return ctx

