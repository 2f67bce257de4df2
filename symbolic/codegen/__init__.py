"""C code of the flight steps, the models and the simulators, with readable APIs.

The package, one module per job: :mod:`~quadland_symbolic.codegen.config` (emitter
settings and the values the C carries), :mod:`~quadland_symbolic.codegen.registry`
(the CasADi functions written as C), :mod:`~quadland_symbolic.codegen.render` (the one
Jinja2 environment), :mod:`~quadland_symbolic.codegen.casadi_files` (CasADi's C,
post-processed), :mod:`~quadland_symbolic.codegen.structs` (the API's structs as
layouts), :mod:`~quadland_symbolic.codegen.paper_api`,
:mod:`~quadland_symbolic.codegen.landing_api`,
:mod:`~quadland_symbolic.codegen.estimator_api` and
:mod:`~quadland_symbolic.codegen.land_detector_api` (the readable APIs),
:mod:`~quadland_symbolic.codegen.example` (the pure-C example),
:mod:`~quadland_symbolic.codegen.tree` (all of ``generated/``) and
:mod:`~quadland_symbolic.codegen.simulator` (the compiled simulators' C;
:mod:`~quadland_symbolic.codegen.time_split` their plants' terms of time alone).

One entry point per tree, :func:`generate` (one precision) and
:func:`generate_tree` (everything under ``generated/``), turns the symbolic
functions into C text:

* one CasADi-generated file per function of the registry
  :data:`FUNCTIONS`, its symbols prefixed for the build, post-processed so
  that each compiles alone with ``-std=c99 -pedantic -Wall -Wextra
  -Werror`` (unused arguments are voided) and, for the single-precision
  build, uses float constants and float math;
* ``quadland.h`` / ``quadland.c`` (named structs, defaults and a checked
  ``ql_control_step`` over CasADi's arg/res arrays) and the named-pointer
  wrappers of the other functions, rendered from the Jinja2 templates in
  ``symbolic/templates/``. Python only builds the templates' context: the
  structs come from the layouts of :mod:`quadland_symbolic.codegen.structs`, offsets and
  sizes from the layouts of the model, defaults as C literals;
* ``example/``: a pure-C flight of the scenario, a benchmark and their
  Makefile.

Every global C symbol carries the build's prefix (:attr:`CodegenConfig.prefix`:
``ql_`` for double, ``qlf_`` for float), CasADi's functions and helpers
included, so that both builds link into one program.

Numeric defaults (a scenario's values) are passed in as :class:`Defaults`;
this package imports nothing from ``quadland``. The output depends only on
its inputs and on the CasADi version, never on time or paths, so
regeneration is byte for byte reproducible.
"""

import importlib

#: The module of each name this package exports. They load on first use (PEP 562):
#: a process that only loads a cached simulator never imports the C writers (Jinja2
#: and the API generators, about 90 ms of CPU).
_EXPORTS = {
    **dict.fromkeys(("DEFAULT_CONFIG", "STATUS_CODES", "TEMPLATE_DIR", "CodegenConfig",
                     "Defaults", "LandingDefaults", "SensorDefaults"), "config"),
    "generate_estimator": "estimator_api",
    **dict.fromkeys(("example_columns", "generate_example", "land_columns"), "example"),
    "generate_land_detector": "land_detector_api",
    "generate_landing": "landing_api",
    "generate": "paper_api",
    **dict.fromkeys(("FUNCTIONS", "GeneratedFunction", "c_sources"), "registry"),
    **dict.fromkeys(("SIMULATOR_PARTS", "loop_header", "simulator_sources"), "simulator"),
    **dict.fromkeys(("TREE_PARTS", "generate_tree"), "tree"),
}


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))


__all__ = ["CodegenConfig", "DEFAULT_CONFIG", "Defaults", "LandingDefaults", "SensorDefaults",
           "GeneratedFunction",
           "FUNCTIONS", "STATUS_CODES", "TEMPLATE_DIR", "c_sources", "example_columns",
           "land_columns", "generate", "generate_landing", "generate_estimator",
           "generate_land_detector",
           "generate_example", "generate_tree", "TREE_PARTS",
           "SIMULATOR_PARTS", "loop_header", "simulator_sources"]
