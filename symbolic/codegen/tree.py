"""Every file of generated/, by relative path."""

from __future__ import annotations

from collections.abc import Mapping

from quadland_symbolic.codegen.config import CodegenConfig, Defaults, LandingDefaults
from quadland_symbolic.codegen.estimator_api import generate_estimator
from quadland_symbolic.codegen.example import generate_example
from quadland_symbolic.codegen.land_detector_api import generate_land_detector
from quadland_symbolic.codegen.landing_api import generate_landing
from quadland_symbolic.codegen.paper_api import generate
from quadland_symbolic.codegen.render import common_context, render

__all__ = ["TREE_PARTS", "generate_tree"]

#: The parts of the generated tree, each a loop's flight code and its C defaults.
TREE_PARTS = ("paper", "landing")


def generate_tree(parts: Mapping[str, Defaults | LandingDefaults]) -> dict[str, str]:
    """Every file of ``generated/`` by relative path (POSIX separators).

    ``parts`` gives each of :data:`TREE_PARTS` its C defaults: the paper's
    step (``"paper"``, :class:`Defaults`) and the landing step
    (``"landing"``, :class:`LandingDefaults`); the navigation filter
    (``quadland_estimator.h``) has no scenario values and is always there. The
    tree holds the double
    build at the top, the float build in ``float/``, the example in
    ``example/`` and a ``.gitignore`` of the example's build outputs.

    Raises
    ------
    ValueError
        When ``parts`` names other parts than :data:`TREE_PARTS`.
    """
    if set(parts) != set(TREE_PARTS):
        raise ValueError(f"the generated tree's parts are {', '.join(TREE_PARTS)}, "
                         f"got {', '.join(map(str, parts))}")
    defaults, landing = parts["paper"], parts["landing"]
    files = {}
    for config, folder in ((CodegenConfig("double"), ""), (CodegenConfig("float"), "float/")):
        built = {**generate(defaults, config), **generate_landing(landing, config),
                 **generate_estimator(config), **generate_land_detector(config)}
        files.update({folder + k: v for k, v in built.items()})
    files.update(generate_example(defaults, landing))
    files[".gitignore"] = render("gitignore.jinja", **common_context(None))
    return files

