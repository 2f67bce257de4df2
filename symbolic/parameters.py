"""Parameter vectors of the model and the controller.

Every builder in ``symbolic`` takes its constants as symbolic parameter
vectors, never as Python numbers, so that the same expressions serve the
simulator, the linearization and generated C code whose gains and physical
constants are tuned at run time without regeneration.

There are three groups, each with a fixed layout:

* ``QUADROTOR``: physical constants of the quadrotor (Table 1, eq. 2);
* ``VEHICLE``: constants and inputs of the ground vehicle (Table 1, eq. 4);
* ``controller_layout(l)``: gains, adaptation constants and RBF network
  (eq. 14, 16, 20, 22); its length depends on the node count ``l``.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

__all__ = [
    "RBF_INPUT_DIM",
    "QUADROTOR",
    "VEHICLE",
    "ParamField",
    "ParamLayout",
    "controller_layout",
]

#: Dimension of the RBF input vartheta (Section 3.2): four velocities and
#: their six pairwise products.
RBF_INPUT_DIM = 10


@dataclasses.dataclass(frozen=True)
class ParamField:
    """One named block of a parameter vector."""

    name: str
    size: int
    unit: str
    doc: str
    shape: tuple[int, int] | None = None
    """Matrix shape (column-major) when the block is a matrix."""


@dataclasses.dataclass(frozen=True)
class ParamLayout:
    """Ordered fields of one parameter vector."""

    name: str
    fields: tuple[ParamField, ...]

    @property
    def size(self) -> int:
        """Total number of scalar entries."""
        return sum(f.size for f in self.fields)

    def offsets(self) -> dict[str, tuple[int, int]]:
        """Map each field name to its ``(start, stop)`` slice."""
        out, start = {}, 0
        for f in self.fields:
            out[f.name] = (start, start + f.size)
            start += f.size
        return out

    def sym(self, name: str | None = None) -> ca.SX:
        """A fresh symbolic column vector of the layout's length."""
        return ca.SX.sym(name or self.name, self.size)

    def unpack(self, p):
        """Split a symbolic or numeric vector into named blocks.

        Matrix blocks are reshaped column-major to their ``shape``.
        """
        if p.shape[0] != self.size:
            raise ValueError(f"{self.name}: expected {self.size} entries, got {p.shape[0]}")
        out = {}
        for f in self.fields:
            a, b = self.offsets()[f.name]
            block = p[a:b]
            if f.shape is not None:
                block = ca.reshape(block, *f.shape) if isinstance(p, ca.SX | ca.MX | ca.DM) \
                    else np.reshape(block, f.shape, order="F")
            out[f.name] = block
        return out

    def pack(self, values: dict) -> np.ndarray:
        """Assemble a numeric vector from a dict of named blocks."""
        missing = [f.name for f in self.fields if f.name not in values]
        if missing:
            raise KeyError(f"{self.name}: missing parameters {missing}")
        chunks = []
        for f in self.fields:
            v = np.asarray(values[f.name], dtype=float)
            flat = v.reshape(-1, order="F") if v.ndim > 1 else np.atleast_1d(v)
            if flat.size != f.size:
                raise ValueError(f"{self.name}.{f.name}: expected {f.size} values, got {flat.size}")
            chunks.append(flat)
        return np.concatenate(chunks)


QUADROTOR = ParamLayout(
    "p_quad",
    (
        ParamField("m1", 1, "kg", "quadrotor mass"),
        ParamField("I", 3, "kg m^2", "principal inertias Ix, Iy, Iz"),
        ParamField("Kt", 3, "N s/m", "translational drag Kt1..Kt3 (body axes)"),
        ParamField("Kr", 3, "N m s/rad", "rotational drag Kr1..Kr3 (body axes)"),
        ParamField("g", 1, "m/s^2", "gravitational acceleration"),
        ParamField("arm", 1, "m", "distance d from the centre to a rotor axis"),
        ParamField("c", 1, "m", "rotor drag factor c (yaw moment per unit thrust)"),
    ),
)

VEHICLE = ParamLayout(
    "p_veh",
    (
        ParamField("m11", 1, "kg", "surge mass"),
        ParamField("m22", 1, "kg", "sway mass"),
        ParamField("m33", 1, "kg m^2", "yaw inertia"),
        ParamField("d11", 1, "kg/s", "surge damping"),
        ParamField("d22", 1, "kg/s", "sway damping"),
        ParamField("d33", 1, "kg m^2/s", "yaw damping"),
        ParamField("tau", 3, "N, N, N m", "inputs tau_x, tau_y, tau_z (eq. 4)"),
        ParamField("z2", 1, "m", "deck altitude (heave is neglected)"),
    ),
)


def controller_layout(l: int) -> ParamLayout:
    """Layout of the controller parameters for an ``l``-node network.

    Parameters
    ----------
    l : int
        Number of RBF nodes (eq. 8).
    """
    if l < 1:
        raise ValueError(f"RBF node count l must be >= 1, got {l}")
    return ParamLayout(
        "p_ctrl",
        (
            ParamField("k1", 4, "1/s", "diagonal of k1 (eq. 14)"),
            ParamField("k2", 4, "1/s", "diagonal of k2 (eq. 20)"),
            ParamField("gamma1", 1, "-", "Gamma1 = gamma1 I_l (eq. 22)"),
            ParamField("gamma2", 1, "-", "Gamma2 = gamma2 I_4 (eq. 22)"),
            ParamField("k_w", 1, "-", "leakage of W_hat (eq. 22)"),
            ParamField("k_zeta", 1, "-", "leakage of zeta_hat (eq. 22)"),
            ParamField("rho", 1, "-", "tanh smoothing width varrho (eq. 20)"),
            ParamField("nominal_model", 1, "0 or 1",
                       "1 feeds forward the quadrotor's known dynamics"),
            ParamField("centers", RBF_INPUT_DIM * l, "-",
                       "RBF centres mu_i as the columns of a 10 x l matrix",
                       shape=(RBF_INPUT_DIM, l)),
            ParamField("widths", l, "-", "RBF widths epsilon_i"),
        ),
    )
