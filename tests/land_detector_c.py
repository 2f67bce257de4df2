"""The land detector's generated C (``quadland_land_detector.h``) loaded with ``ctypes``,
for the tests.

The library is built from the same text ``generated/`` holds (the landing's flight
files, which carry every header it includes), with the structs' ``ctypes`` mirrors
built from the same layouts as the C.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools

import numpy as np

from quadland.engine.build import build_library
from quadland.engine.flightcode import Library, ctypes_struct, real_type
from quadland.kinds.landing.flight import flight_files
from quadland_symbolic.codegen import CodegenConfig, c_sources
from quadland_symbolic.codegen.estimator_api import estimator_api_structs
from quadland_symbolic.codegen.land_detector_api import land_detector_api_structs
from quadland_symbolic.codegen.structs import api_structs, landing_api_structs

#: The landing's node count whose flight files generated/ carries (highway's).
L = 10


def files(precision: str) -> dict[str, str]:
    """Every C file of one build (the detector's among the landing's flight files)."""
    return flight_files(L, precision)


def sources() -> tuple[str, ...]:
    """The ``.c`` files of the detector's API."""
    return c_sources(("land_detector",))


@dataclasses.dataclass(frozen=True)
class DetectorApi:
    """The detector's API: the library (``ql_`` names in either precision), the struct
    mirrors by their C names without prefix, the real type and its NumPy dtype."""

    lib: object
    structs: dict
    real: type
    dtype: type


@functools.lru_cache(maxsize=2)
def load(precision: str = "double") -> DetectorApi:
    """The detector's API of one precision, compiled (-O2) and loaded."""
    config = CodegenConfig(precision)
    lib = Library(ctypes.CDLL(str(build_library(files(precision), sources()))), config.prefix)
    real = real_type(precision)
    structs = {s.name: ctypes_struct(s.layout, real)
               for s in (*api_structs(1), *landing_api_structs(L), *estimator_api_structs(),
                         *land_detector_api_structs())}
    P = ctypes.POINTER
    lib.ql_land_detector_step.argtypes = [P(structs["land_detector_cues"]),
                                          P(structs["land_detector_params"]), real,
                                          P(structs["land_detector_state"]),
                                          P(structs["land_detector_flags"])]
    lib.ql_land_detector_form_cues.argtypes = [
        P(structs["landing_measurement"]), P(structs["range_packet"]), P(structs["imu"]),
        P(real), P(structs["guidance_state"]), P(structs["guidance_params"]),
        P(structs["quadrotor_params"]), P(structs["land_detector_cues"])]
    lib.ql_check_land_detector_params.argtypes = [P(structs["land_detector_params"]),
                                                  P(ctypes.c_char_p)]
    for name in ("ql_land_detector_step", "ql_land_detector_form_cues",
                 "ql_check_land_detector_params"):
        getattr(lib, name).restype = ctypes.c_int
    lib.ql_land_detector_params_init.argtypes = [P(structs["land_detector_params"])]
    lib.ql_land_detector_state_init.argtypes = [P(structs["land_detector_state"])]
    dtype = np.float64 if precision == "double" else np.float32
    return DetectorApi(lib=lib, structs=structs, real=real, dtype=dtype)


def view(struct, dtype) -> np.ndarray:
    """A NumPy view on the reals of a ``ctypes`` struct (its int members left out)."""
    n = sum(ctypes.sizeof(t) // np.dtype(dtype).itemsize if not issubclass(t, ctypes.c_int)
            else 0 for _, t in struct._fields_)
    return np.frombuffer((ctypes.c_char * ctypes.sizeof(struct)).from_buffer(struct),
                         dtype=dtype, count=n)


class Call:
    """One set of arguments of ``ql_land_detector_step``, with NumPy views on each.

    ``v[name]`` views ``cues``, ``params``, ``state`` and ``flags``.
    """

    ARGS = ("cues", "params", "state", "flags")

    def __init__(self, api: DetectorApi):
        self.api = api
        types = dict(cues="land_detector_cues", params="land_detector_params",
                     state="land_detector_state", flags="land_detector_flags")
        self.s = {n: api.structs[types[n]]() for n in self.ARGS}
        self.v = {n: view(self.s[n], api.dtype) for n in self.ARGS}
        api.lib.ql_land_detector_params_init(ctypes.byref(self.s["params"]))
        api.lib.ql_land_detector_state_init(ctypes.byref(self.s["state"]))

    def step(self, dt: float, null=()) -> int:
        args = [None if n in null else ctypes.byref(self.s[n]) for n in self.ARGS]
        return self.api.lib.ql_land_detector_step(args[0], args[1], dt, args[2], args[3])

    def check(self):
        bad = ctypes.c_char_p()
        status = self.api.lib.ql_check_land_detector_params(ctypes.byref(self.s["params"]),
                                                            ctypes.byref(bad))
        return status, None if bad.value is None else bad.value.decode()
