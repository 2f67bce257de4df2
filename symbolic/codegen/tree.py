"""Every file of generated/, by relative path."""

from __future__ import annotations

from quadland_symbolic.codegen.config import CodegenConfig, Defaults, LandingDefaults
from quadland_symbolic.codegen.example import generate_example
from quadland_symbolic.codegen.landing_api import generate_landing
from quadland_symbolic.codegen.paper_api import generate
from quadland_symbolic.codegen.render import common_context, render

__all__ = ["generate_tree"]


def generate_tree(defaults: Defaults, landing: LandingDefaults) -> dict[str, str]:
    """Every file of ``generated/`` by relative path (POSIX separators).

    The paper's step (``defaults``) and the landing step (``landing``), the
    double build at the top, the float build in ``float/``, the example in
    ``example/`` and a ``.gitignore`` of the example's build outputs.
    """
    files = {}
    for config, folder in ((CodegenConfig("double"), ""), (CodegenConfig("float"), "float/")):
        built = {**generate(defaults, config), **generate_landing(landing, config)}
        files.update({folder + k: v for k, v in built.items()})
    files.update(generate_example(defaults, landing))
    files[".gitignore"] = render("gitignore.jinja", **common_context(None))
    return files

