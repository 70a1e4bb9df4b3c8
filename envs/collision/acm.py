"""Allowed-collision matrix (ACM), generated the way MoveIt's setup assistant does it, and cached.

A pair of links is *disabled* (never checked for self-collision) when it is

* ``adjacent``: parent and child in the kinematic tree, after links without geometry are contracted (their
  parent and children become adjacent, as MoveIt's connection graph does);
* ``always``: in collision in at least ``ALWAYS_FRACTION`` (95%) of the sampled configurations;
* ``never``: in collision in none of ``ACM_SAMPLES`` (10,000) configurations drawn uniformly within the joint
  limits (MoveIt's default sampling density).

Every other pair stays enabled, in particular one that collides in some but not most samples. MoveIt also
disables pairs in collision in the default pose; that rule is left out here because such a pair can be in the
enabled band, and checking it costs less than missing it.

The samples use the unpadded geometry at the requested fidelity. :func:`load_acm` gives the coarse levels
(``COARSE_LEVELS``) no matrix of their own: their shapes overlap around most joints in most poses, so their own
samples would leave pairs enabled that the links themselves touch in few poses or none. They share
``CONFIRM_LEVEL``'s, whose shapes also confirm their self-collision hits (:mod:`confirm`); ``auto`` shares
``mesh``'s. Results are cached as JSON keyed by the URDF's content (and its meshes'), the fidelity and the sampling
settings: first among the files shipped in ``clutter_gym/assets/acm/``, then in the user cache
(``$XDG_CACHE_HOME/clutter-gym/acm``, default ``~/.cache/clutter-gym/acm``), else generated (seconds) and written
there atomically; a cached file that does not read back as the matrix of its key is generated again. The shipped
files (the Panda's and the diffbot's at ``convex`` and ``mesh``, the two levels :func:`load_acm` reads) are
regenerated with ``save_acm(generate_acm(urdf, level), urdf, SHIPPED_DIR)``; a test fails when they no longer match
their URDFs.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import fcl
import numpy as np

from clutter_gym.assets import ASSET_DIR
from clutter_gym.collision.fidelity import COARSE_LEVELS, CONFIRM_LEVEL, build_link_shapes, check_fidelity
from clutter_gym.urdf.geometry import load_collision_elements, urdf_digest
from clutter_gym.urdf.kinematics import UrdfKinematics
from clutter_gym.util.atomic import write_text_atomically
from clutter_gym.util.cache_dir import user_cache_dir

ACM_SAMPLES = 10_000
ALWAYS_FRACTION = 0.95
ACM_SEED = 0
ALGORITHM = 1  # bump when the rules change: old cache files stop matching
SHIPPED_DIR = ASSET_DIR / "acm"

Pair = tuple[str, str]


def pair(a: str, b: str) -> Pair:
    return (a, b) if a <= b else (b, a)


@dataclass(frozen=True)
class AllowedCollisionMatrix:
    """Which link pairs are checked for self-collision, and why the others are not.

    Attributes:
        links: links with collision geometry.
        disabled: reason per disabled pair: "adjacent", "always" or "never".
        fraction: share of the samples in which each non-adjacent pair collided.
        samples: number of sampled configurations.
        key: the cache key (URDF digest, fidelity and settings).
    """

    links: tuple[str, ...]
    disabled: dict[Pair, str]
    fraction: dict[Pair, float]
    samples: int
    key: str

    @property
    def enabled(self) -> tuple[Pair, ...]:
        """Pairs checked for self-collision, sorted."""
        every = (pair(a, b) for i, a in enumerate(self.links) for b in self.links[i + 1:])
        return tuple(sorted(p for p in every if p not in self.disabled))

    def to_json(self) -> str:
        return json.dumps(
            {
                "key": self.key,
                "samples": self.samples,
                "links": list(self.links),
                "disabled": [[a, b, reason] for (a, b), reason in sorted(self.disabled.items())],
                "fraction": [[a, b, f] for (a, b), f in sorted(self.fraction.items())],
            },
            indent=1,
        )

    @classmethod
    def from_json(cls, text: str) -> AllowedCollisionMatrix:
        data = json.loads(text)
        return cls(
            links=tuple(data["links"]),
            disabled={(a, b): reason for a, b, reason in data["disabled"]},
            fraction={(a, b): float(f) for a, b, f in data["fraction"]},
            samples=int(data["samples"]),
            key=data["key"],
        )


def adjacent_pairs(kinematics: UrdfKinematics, geometric: Sequence[str]) -> set[Pair]:
    """Parent/child pairs of links with geometry, with geometry-less links contracted."""
    geometric = set(geometric)
    children: dict[str, list[str]] = {}
    for child, parent in kinematics.parent.items():
        children.setdefault(parent, []).append(child)

    def geometric_below(link: str) -> list[str]:  # nearest links with geometry under ``link``
        out = []
        for c in children.get(link, []):
            out.extend([c] if c in geometric else geometric_below(c))
        return out

    pairs = set()
    for link in kinematics.links:
        below = geometric_below(link)
        if link in geometric:
            pairs.update(pair(link, c) for c in below)
        else:  # a geometry-less link joins its neighbours: its children with each other ...
            pairs.update(pair(a, b) for i, a in enumerate(below) for b in below[i + 1:])
            up = kinematics.parent.get(link)
            while up is not None and up not in geometric:
                up = kinematics.parent.get(up)
            if up is not None:  # ... and with its nearest geometric ancestor
                pairs.update(pair(up, c) for c in below)
    return pairs


def acm_key(urdf: str | Path, fidelity: str, samples: int, seed: int) -> str:
    return f"{urdf_digest(urdf)[:20]}-{fidelity}-n{samples}-s{seed}-a{ALGORITHM}-f{ALWAYS_FRACTION}"


def generate_acm(
    urdf: str | Path, fidelity: str, samples: int = ACM_SAMPLES, seed: int = ACM_SEED
) -> AllowedCollisionMatrix:
    """Sample ``samples`` configurations (numpy FK, uniform within the joint limits) and classify every pair."""
    from clutter_gym.collision.robot_model import RobotCollisionModel  # it imports this module: import late

    check_fidelity(fidelity)
    kinematics = UrdfKinematics(urdf)
    shapes = build_link_shapes(load_collision_elements(urdf), fidelity)
    model = RobotCollisionModel(shapes, kinematics.links)
    links = model.links
    adjacent = adjacent_pairs(kinematics, links)
    candidates = [pair(a, b) for i, a in enumerate(links) for b in links[i + 1:] if pair(a, b) not in adjacent]
    rng = np.random.default_rng(seed)
    q = rng.uniform(kinematics.lower, kinematics.upper, size=(samples, len(kinematics.joints)))
    hits = _count_collisions(model, kinematics, q, candidates)
    fraction = {p: hits[p] / samples for p in candidates}
    disabled: dict[Pair, str] = dict.fromkeys(adjacent, "adjacent")
    for p, f in fraction.items():
        if f >= ALWAYS_FRACTION:
            disabled[p] = "always"
        elif hits[p] == 0:
            disabled[p] = "never"
    return AllowedCollisionMatrix(links, disabled, fraction, samples, acm_key(urdf, fidelity, samples, seed))


def _count_collisions(model, kinematics: UrdfKinematics, q: np.ndarray, candidates: list[Pair]) -> dict[Pair, int]:
    frames = kinematics.forward(q)
    positions = np.stack([frames[name][:, :3, 3] for name in kinematics.links], axis=1)  # (n, L, 3)
    rotations = np.stack([frames[name][:, :3, :3] for name in kinematics.links], axis=1)
    shape_pairs = {
        p: [(i, j) for i, si in enumerate(model.shapes) for j, sj in enumerate(model.shapes)
            if i < j and pair(si.link, sj.link) == p]
        for p in candidates
    }
    flat = [(p, i, j) for p, ij in shape_pairs.items() for i, j in ij]
    first = np.array([i for _, i, _ in flat], dtype=int)
    second = np.array([j for _, _, j in flat], dtype=int)
    reach = np.array([s.radius for s in model.shapes])
    request, hits = fcl.CollisionRequest(), dict.fromkeys(candidates, 0)
    for n in range(len(q)):
        model.sync(positions[n], rotations[n])
        gap = np.linalg.norm(model.position[first] - model.position[second], axis=1) - reach[first] - reach[second]
        seen = set()
        for k in np.flatnonzero(gap <= 0.0):
            p, i, j = flat[k]
            if p not in seen and fcl.collide(model.object(i), model.object(j), request, fcl.CollisionResult()):
                seen.add(p)
                hits[p] += 1
    return hits


def load_acm(urdf: str | Path, fidelity: str, samples: int = ACM_SAMPLES,
             seed: int = ACM_SEED) -> AllowedCollisionMatrix:
    """The cached ACM of ``urdf`` at ``fidelity`` (shipped or user cache), generating and caching it if absent.
    Which link pairs can touch is a property of the robot: ``auto`` shares ``mesh``'s, which it models to within
    ``AUTO_HULL_TOLERANCE``, and the coarse levels (``COARSE_LEVELS``) share ``CONFIRM_LEVEL``'s, whose shapes
    confirm their self-collision hits (their own shapes overlap around most joints in most poses)."""
    if fidelity in COARSE_LEVELS:
        fidelity = CONFIRM_LEVEL
    elif fidelity == "auto":
        fidelity = "mesh"
    key = acm_key(urdf, fidelity, samples, seed)
    name = f"{Path(urdf).stem}-{key}.json"
    for folder in (SHIPPED_DIR, user_cache_dir("acm")):
        acm = _read_acm(folder / name, key)
        if acm is not None:
            return acm
    acm = generate_acm(urdf, fidelity, samples, seed)
    try:
        save_acm(acm, urdf, user_cache_dir("acm"))  # over a corrupt file of the same name, if there was one
    except OSError:  # a full disk still gets a working (uncached) ACM
        pass
    return acm


def _read_acm(path: Path, key: str) -> AllowedCollisionMatrix | None:
    """The ACM cached at ``path`` when it is one of ``key`` whose pairs are pairs of its links; None when there is
    no such file, or it is corrupt (cut short, edited, of another layout): it is then generated again."""
    try:
        acm = AllowedCollisionMatrix.from_json(path.read_text())
        links = set(acm.links)
        pairs_known = all(a in links and b in links for a, b in (*acm.disabled, *acm.fraction))
        reasons_known = set(acm.disabled.values()) <= {"adjacent", "always", "never"}
    # missing, or not what to_json writes (a JSONDecodeError or UnicodeDecodeError is a ValueError)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return acm if acm.key == key and pairs_known and reasons_known else None


def save_acm(acm: AllowedCollisionMatrix, urdf: str | Path, folder: Path) -> Path:
    """Write ``acm`` where :func:`load_acm` looks for it (``folder`` = ``SHIPPED_DIR`` to ship it), atomically."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{Path(urdf).stem}-{acm.key}.json"
    write_text_atomically(path, acm.to_json())
    return path
