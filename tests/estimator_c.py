"""The navigation filter's generated C (``quadland_estimator.h``) loaded with ``ctypes``,
for the tests.

The library is built from the same text ``generated/`` holds (the landing's flight
files, which carry ``quadland_landing.h``, and :func:`generate_estimator`), with the
structs' ``ctypes`` mirrors built from the same layouts as the C.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools

import numpy as np

from quadland.engine.build import build_library
from quadland.engine.flightcode import Library, ctypes_struct, real_type
from quadland.kinds.landing.flight import flight_files
from quadland_symbolic.codegen import CodegenConfig, c_sources, generate_estimator
from quadland_symbolic.codegen.estimator_api import estimator_api_structs
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.navigation import SENSORS

#: The landing's node count whose flight files carry quadland_landing.h (highway's).
L = 10


def files(precision: str) -> dict[str, str]:
    """Every C file of one build: the landing's flight files and the filter's."""
    return {**flight_files(L, precision), **generate_estimator(CodegenConfig(precision))}


def sources() -> tuple[str, ...]:
    """The ``.c`` files of the filter's API."""
    return c_sources(("estimator_step",))


@dataclasses.dataclass(frozen=True)
class EstimatorApi:
    """The filter's API: the library (``ql_`` names in either precision), the struct
    mirrors by their C names without prefix, and the real type."""

    lib: object
    structs: dict
    real: type
    dtype: type


@functools.lru_cache(maxsize=2)
def load(precision: str = "double") -> EstimatorApi:
    """The filter's API of one precision, compiled (-O2) and loaded."""
    config = CodegenConfig(precision)
    lib = Library(ctypes.CDLL(str(build_library(files(precision), sources()))), config.prefix)
    real = real_type(precision)
    structs = {s.name: ctypes_struct(s.layout, real) for s in estimator_api_structs()}
    structs["landing_measurement"] = ctypes_struct(LANDING_MEASUREMENT, real)
    P = ctypes.POINTER
    lib.ql_estimator_step.argtypes = [P(structs["imu"]),
                                      *[P(structs[f"{s}_packet"]) for s in SENSORS],
                                      P(structs["estimator_params"]), real, real,
                                      P(structs["estimator_memory"]),
                                      P(structs["landing_measurement"]),
                                      P(structs["estimator_diagnostics"])]
    lib.ql_estimator_init.argtypes = [P(structs["nav_state"]), P(real), P(structs["deck_init"]),
                                      real, P(structs["estimator_memory"])]
    lib.ql_check_estimator_params.argtypes = [P(structs["estimator_params"]),
                                              P(ctypes.c_char_p)]
    for name in ("ql_estimator_step", "ql_estimator_init", "ql_check_estimator_params"):
        getattr(lib, name).restype = ctypes.c_int
    lib.ql_estimator_params_init.argtypes = [P(structs["estimator_params"])]
    dtype = np.float64 if precision == "double" else np.float32
    return EstimatorApi(lib=lib, structs=structs, real=real, dtype=dtype)


def view(struct, dtype) -> np.ndarray:
    """A NumPy view on every real of a ``ctypes`` struct (no int members here)."""
    n = ctypes.sizeof(struct) // np.dtype(dtype).itemsize
    return np.frombuffer((ctypes.c_char * ctypes.sizeof(struct)).from_buffer(struct),
                         dtype=dtype, count=n)


class Call:
    """One set of arguments of ``ql_estimator_step``, with NumPy views on each.

    ``v[name]`` views ``imu``, the packets (by sensor), ``params``, ``mem``, ``y``
    and ``diag``.
    """

    ARGS = ("imu", *SENSORS, "params", "mem", "y", "diag")

    def __init__(self, api: EstimatorApi):
        self.api = api
        types = dict(imu="imu", params="estimator_params", mem="estimator_memory",
                     y="landing_measurement", diag="estimator_diagnostics",
                     **{s: f"{s}_packet" for s in SENSORS})
        self.s = {n: api.structs[types[n]]() for n in self.ARGS}
        self.v = {n: view(self.s[n], api.dtype) for n in self.ARGS}
        api.lib.ql_estimator_params_init(ctypes.byref(self.s["params"]))

    def init(self, x0, P0_diag, deck0, t0) -> int:
        api, real = self.api, self.api.real
        x = api.structs["nav_state"]()
        view(x, api.dtype)[:] = x0
        P = (real * len(P0_diag))(*P0_diag)
        d = None
        if deck0 is not None:
            d = api.structs["deck_init"]()
            view(d, api.dtype)[:] = deck0
        return api.lib.ql_estimator_init(ctypes.byref(x), P, None if d is None else
                                         ctypes.byref(d), t0, ctypes.byref(self.s["mem"]))

    def step(self, dt: float, t: float, null=()) -> int:
        args = [ctypes.byref(self.s[n]) for n in self.ARGS]
        args[self.ARGS.index("params") + 1:self.ARGS.index("params") + 1] = [dt, t]
        for name in null:
            i = self.ARGS.index(name)
            args[i if i <= self.ARGS.index("params") else i + 2] = None
        return self.api.lib.ql_estimator_step(*args)

    def check(self):
        bad = ctypes.c_char_p()
        status = self.api.lib.ql_check_estimator_params(ctypes.byref(self.s["params"]),
                                                        ctypes.byref(bad))
        return status, None if bad.value is None else bad.value.decode()
