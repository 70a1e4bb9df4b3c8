""":class:`WorldRecord`: what a :class:`~clutter_gym.sim.Sim` has made in its pybullet world, the one state its parts
share.

pybullet's client does not list the bodies made in batches, does not say which collision filter or shapes a body
was given, and frees no shape; the Sim's parts (:mod:`.actuation`, :mod:`.obstacles`, :mod:`.rays`,
:mod:`.rendering`) each take this record explicitly instead of reading one another's fields.
"""

from __future__ import annotations

import pybullet as pb

from clutter_gym.sim.primitives import PrimitiveTable
from clutter_gym.util.view_culling import ViewCuller


class WorldRecord:
    """The client id and the bodies, shapes and filters made through it (see the module docstring).

    Args:
        cid: the pybullet client id (-1 once the Sim is closed: every part then fails in pybullet, never acts on
            another client that reused the id).
        visuals: the Sim's obstacles have visual shapes (:class:`~clutter_gym.sim.Sim`'s ``visuals``).

    Attributes:
        version: counts every change that may change what a ray can hit; never reset, so a cache keyed on it
            stays valid across :meth:`clear`.
        bodies: body id of each named body.
        body_ids: every body made or loaded here.
        freed: removed body ids pybullet has not given out again (it reuses those first).
        filters: body -> (collision group, mask) set here.
        shapes: (kind, sizes, rgba) -> (collision, visual) shape ids, made once and shared.
        colours: body -> (link, rgba) of its visual shapes, read once (the camera hides and shows them).
        removed_bodies: bodies removed since the world was last emptied.
        ground: the ground plane's body id (-1: none).
        culler: bounding spheres and colours of the static bodies, for the camera's view culling.
        primitives: the boxes, cylinders, ground and markers the exact ray caster and ray-cast camera see.
    """

    def __init__(self, cid: int, visuals: bool) -> None:
        self.cid, self.visuals = cid, visuals
        self.version = 0
        self.clear()

    def clear(self) -> None:
        """Forget every body and shape (the world was emptied)."""
        self.bodies: dict[str, int] = {}
        self.body_ids: set[int] = set()
        self.freed: set[int] = set()
        self.filters: dict[int, tuple[int, int]] = {}
        self.shapes: dict[tuple, tuple[int, int]] = {}
        self.colours: dict[int, list[tuple[int, tuple]]] = {}
        self.removed_bodies = 0
        self.ground = -1
        self.culler = ViewCuller()
        self.primitives = PrimitiveTable()
        self.version += 1

    def made(self, bodies: list[int] | tuple[int, ...]) -> None:
        """Record bodies just made or loaded."""
        self.body_ids.update(bodies)
        self.freed.difference_update(bodies)
        self.version += 1

    def removed(self, body: int) -> None:
        """Forget a body just removed from the world; pybullet may give its id out again."""
        self.culler.remove(body)
        self.primitives.remove(body)
        self.colours.pop(body, None)
        self.body_ids.discard(body)
        if body == self.ground:
            self.ground = -1
        self.freed.add(body)
        self.removed_bodies += 1
        self.version += 1

    def forget_contacts(self, body: int) -> None:
        """Drop Bullet's cached contact manifolds of ``body`` (call after teleporting it).

        Bullet keeps a pair's contact points, and the impulses it warm-starts the solver with, for as long as the
        points stay within the breaking threshold. A body reset to where it just was would start its episode
        warm-started from the last one, so the same seed would not give the same trajectory. Re-applying the
        collision filter re-registers the link colliders with the broad phase, which deletes their pairs. Only
        bodies whose filter was set here (``Rays.hide_from_rays``, the movable bodies) can be re-registered.
        """
        if body not in self.filters:
            raise ValueError(f"body {body} has no recorded collision filter; call hide_from_rays first")
        self.apply_filter(body)

    def apply_filter(self, body: int) -> None:
        """Set every link of ``body`` to its recorded collision group and mask."""
        group, mask = self.filters[body]
        for link in range(-1, pb.getNumJoints(body, physicsClientId=self.cid)):
            pb.setCollisionFilterGroupMask(body, link, group, mask, physicsClientId=self.cid)
