"""The augmented Lagrangian's contact multiplier lambda on Gamma3 (physics/contact.py has the
terms it enters): Uzawa's update lambda <- (lambda + u_N/d_N)^+ once the iterate has settled."""
from __future__ import annotations

import dolfinx.fem
import numpy as np

from forming_fenicsx.core.compat import function_space, petsc_vec
from forming_fenicsx.fem.projection import LumpedProjector
from forming_fenicsx.mesh.transfer import transfer
from forming_fenicsx.physics.contact import contact_pressure


class ContactMultiplier:
    """The augmented Lagrangian's multiplier lambda on the traces of P1 on Gamma3 (zero elsewhere).

    Uzawa's update sets lambda to the nodal mean (lumped projection, non-negative) of
    (lambda + u_N/d_N)^+ over the die at the velocity ``state``. The solvers update it once their
    iterate has nearly settled (``settled``): an inexact augmented Lagrangian; updating after every
    iterate lets lambda grow while a damped iteration barely moves u, and diverges."""

    # update once the iterate's increment is below WINDOW * delta; end once the update would change
    # lambda by less than WINDOW * delta (relative, nodal values)
    WINDOW = 100.0

    def __init__(self, state: dolfinx.fem.Function, n, d_N: float, ds_contact, degree: int):
        self.value = dolfinx.fem.Function(function_space(state.function_space.mesh, "P", 1),
                                          name="contact_multiplier")
        self._projector = LumpedProjector(contact_pressure(state, n, d_N, self.value), self.value,
                                          degree, ds_contact)
        self._before = petsc_vec(self.value).duplicate()
        self.updates = 0

    def update(self, keep_below: float = 0.0) -> float:
        """lambda <- (lambda + u_N/d_N)^+ at the current state, unless that changes lambda by less
        than ``keep_below``; returns the relative change
        ||lambda_new - lambda|| / ||lambda_new||."""
        vector, before = petsc_vec(self.value), self._before
        vector.copy(before)
        self._projector.project()
        norm = vector.norm()
        before.axpy(-1.0, vector)
        change = before.norm() / norm if norm > 0 else 0.0
        if change < keep_below:  # before held lambda_old - lambda_new: restore lambda_old
            vector.axpy(1.0, before)
            self.value.x.scatter_forward()
        else:
            self.updates += 1
        return change

    def start_from(self, source: dolfinx.fem.Function, nodal: bool = False) -> None:
        """lambda of a solved problem on another mesh of the workpiece (a warm start): the
        source multiplier at this one's nodes of Gamma3 (transfer.py; node for node on a mesh of
        the source's layout, ``nodal``), zero elsewhere as after an update."""
        transfer(source, self.value, nodal)
        owned = self.value.function_space.dofmap.index_map.size_local
        self.value.x.array[:owned] *= self._projector.weights_mask()
        self.value.x.array[:owned] = np.maximum(self.value.x.array[:owned], 0.0)
        self.value.x.scatter_forward()

    def settled(self, increment: float, delta: float) -> bool:
        """Called after every iterate (increment: its relative change, taken in full): updates
        lambda once the increment is below WINDOW * delta; True when lambda needs no update (a
        change below WINDOW * delta), so that the iteration may end."""
        if increment >= self.WINDOW * delta:
            return False
        return self.update(keep_below=self.WINDOW * delta) < self.WINDOW * delta
