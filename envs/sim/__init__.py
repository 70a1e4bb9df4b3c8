"""The one gateway to pybullet (docs/architecture.md, "Rules"): a physics client, bodies by name, batched reads.

Every pybullet call in clutter-gym goes through :class:`Sim`. It passes its own ``physicsClientId`` to pybullet
directly rather than going through ``pybullet_utils.BulletClient``, which adds overhead to every call
(docs/design-notes.md#no-bulletclient). :mod:`.core` holds the client, loading and the hot path's reads; its parts
are objects on one shared :mod:`.world_record`: ``sim.actuation`` (:mod:`.actuation`), ``sim.obstacles``
(:mod:`.obstacles`), ``sim.rays`` (:mod:`.rays`) and ``sim.rendering`` (:mod:`.rendering`).

pybullet prints its build banner (stderr) and URDF/shape warnings (stdout) from C, straight to the file
descriptors; :func:`~clutter_gym.util.quiet.quiet_c_output` silences them around the calls that print, so output
stays readable. pybullet is first imported here, quietly.
"""

from clutter_gym.util.quiet import quiet_c_output

with quiet_c_output():
    import pybullet as pb

from clutter_gym.sim.core import GRAVITY, Sim, pybullet_data_file  # noqa: E402  (after the quiet import)
from clutter_gym.sim.obstacles import CYLINDER_SIDES, MAX_BODY_BATCH  # noqa: E402
from clutter_gym.sim.rays import MAX_RAY_BATCH, RAY_CASTERS, RAY_INVISIBLE_GROUP  # noqa: E402

__all__ = ["CYLINDER_SIDES", "GRAVITY", "MAX_BODY_BATCH", "MAX_RAY_BATCH", "RAY_CASTERS", "RAY_INVISIBLE_GROUP",
           "Sim", "pb", "pybullet_data_file"]
