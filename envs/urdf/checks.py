"""What a URDF must be before anything reads it further: a tree of named links and joints, whose numbers are finite,
whose masses and moments are not negative, and which holds no xacro left unexpanded.

pybullet's ``loadURDF`` trusts what it is given: a link that is the child of two joints crashes it (a segfault), and
a NaN mass reaches the physics and FCL, which crash at the first step. This package's own readers assumed a tree as
well (a kinematic cycle made the kinematics' breadth-first walk run until memory ran out). Every reader of a URDF in
the package (the kinematics, the collision elements, the mass properties, the prepared copy a spec's robot loads)
parses it through :func:`~clutter_gym.urdf.geometry.parse_urdf`, which runs :func:`check_urdf`; so no URDF
a user passes reaches pybullet unless it passes these checks. Each refusal is one line naming the file, the link or
joint and the element. What a robot of a given kind needs beyond this (wheels, arm joints, rotors) its spec reader
checks (``robots/``).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator

#: How many numbers each numeric attribute of a URDF element holds, by the element's tag (the attributes pybullet
#: reads as numbers; ``value`` is the one attribute of mass and of every ``<contact>`` setting).
NUMBERS: dict[str, dict[str, int]] = {
    "origin": {"xyz": 3, "rpy": 3},
    "axis": {"xyz": 3},
    "mass": {"value": 1},
    "inertia": dict.fromkeys(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), 1),
    "box": {"size": 3},
    "cylinder": {"radius": 1, "length": 1},
    "capsule": {"radius": 1, "length": 1},
    "sphere": {"radius": 1},
    "mesh": {"scale": 3},
    "color": {"rgba": 4},
    "limit": dict.fromkeys(("lower", "upper", "effort", "velocity"), 1),
    "dynamics": {"damping": 1, "friction": 1},
    "joint_properties": {"damping": 1, "friction": 1},
    "safety_controller": dict.fromkeys(("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"), 1),
    "mimic": {"multiplier": 1, "offset": 1},
    **{tag: {"value": 1} for tag in ("lateral_friction", "rolling_friction", "spinning_friction", "restitution",
                                     "stiffness", "damping", "contact_cfm", "contact_erp", "inertia_scaling")},
}
#: Top-level elements pybullet does not read (simulator plugins, ROS control): left unchecked.
UNREAD = ("gazebo", "transmission")
#: Links a URDF may have: the registered robots have at most 13 and pybullet_data's largest robot 31. A make's time
#: grows with the square of the links with collision geometry (the allowed-collision matrix samples every pair), so a
#: 1 MB file of links would make for hours; docs/robots.md gives the figures.
MAX_LINKS = 128
#: An element nested deeper than this is refused: a URDF is about six deep, and the standard library's XML writer
#: and copier recurse once per level.
MAX_DEPTH = 32
_OPTENV = re.compile(r"\$\(optenv\s+\S+\s*([^)]*)\)")
_XACRO = re.compile(r"\$[({][^)}]*[)}]?")
#: A number as pybullet's parser reads one (Python's float() also takes "1_000", "nan" and "infinity").
_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def resolve_optenv(root: ET.Element) -> None:
    """Replace every ``$(optenv NAME default)`` xacro left in an attribute by its default, never by the environment
    variable: a URDF must not change with a shell variable (pybullet_data's Husky keeps a few)."""
    for element in root.iter():
        for key, value in element.attrib.items():
            if "$(" in value:
                element.set(key, _OPTENV.sub(lambda match: match.group(1).strip(), value))


def check_urdf(root: ET.Element, urdf: object) -> None:
    """Refuse a URDF (parsed as ``root``, read from ``urdf``) that is not a tree of uniquely named links and joints
    with one root, or whose elements hold a number that is not finite, a negative mass or moment of inertia, or an
    unexpanded xacro substitution.

    Raises:
        ValueError: one line naming ``urdf``, the link or joint and the element.
    """
    if root.tag != "robot":
        raise ValueError(f"{urdf}: not a URDF: its top element is <{root.tag}>, not <robot>")
    links = _names(root, "link", urdf)
    if not 0 < len(links) <= MAX_LINKS:
        raise ValueError(f"{urdf}: has {len(links)} links; a URDF here has 1 to {MAX_LINKS}")
    joints = _names(root, "joint", urdf)
    parent_joint: dict[str, tuple[str, str]] = {}  # link -> (the joint it hangs from, that joint's parent link)
    children: dict[str, list[str]] = {}
    for name, joint in joints.items():
        parent, child = (_joint_link(joint, end, name, links, urdf) for end in ("parent", "child"))
        if parent == child:
            raise ValueError(f"{urdf}: joint {name!r} joins link {child!r} to itself")
        if child in parent_joint:
            raise ValueError(f"{urdf}: link {child!r} is the child of two joints, {parent_joint[child][0]!r} and "
                             f"{name!r}; a URDF is a tree: each link hangs from one joint")
        parent_joint[child] = (name, parent)
        children.setdefault(parent, []).append(child)
    roots = [link for link in links if link not in parent_joint]
    if len(roots) > 1:
        raise ValueError(f"{urdf}: {len(roots)} links hang from no joint ({_few(roots)}); a URDF has one root "
                         "link: join the others to it")
    reached = set(roots)
    frontier = list(roots)
    while frontier:
        for child in children.get(frontier.pop(), []):
            reached.add(child)
            frontier.append(child)
    if len(reached) < len(links):
        loop = _cycle(next(link for link in links if link not in reached), parent_joint)
        raise ValueError(f"{urdf}: joints {_few(loop)} form a kinematic cycle{' and leave no root link' * (not roots)}"
                         "; a URDF is a tree: one root link, every other link reached from it by one path")
    for where, element in _elements(root, urdf):
        _check_element(element, f"{urdf}: {where}")


def _names(root: ET.Element, tag: str, urdf: object) -> dict[str, ET.Element]:
    """The ``<tag>`` children of ``root`` by name, refusing one without a name and a name given twice."""
    named: dict[str, ET.Element] = {}
    for i, element in enumerate(root.findall(tag)):
        name = element.get("name")
        if not name:
            raise ValueError(f"{urdf}: <{tag}> number {i + 1} has no name; every {tag} needs a unique name")
        if name in named:
            raise ValueError(f"{urdf}: two {tag}s are named {name!r}; {tag} names must be unique")
        named[name] = element
    return named


def _joint_link(joint: ET.Element, end: str, name: str, links: dict[str, ET.Element], urdf: object) -> str:
    element = joint.find(end)
    link = element.get("link") if element is not None else None
    if not link:
        raise ValueError(f"{urdf}: joint {name!r} has no <{end} link=...>")
    if link not in links:
        raise ValueError(f"{urdf}: joint {name!r} names {end} link {link!r}, which is not a <link> of the URDF")
    return link


def _cycle(link: str, parent_joint: dict[str, tuple[str, str]]) -> list[str]:
    """The joints of the cycle found by walking up from ``link``, which the root does not reach."""
    seen: list[str] = []
    while link not in seen:
        seen.append(link)
        link = parent_joint[link][1]
    return [parent_joint[child][0] for child in seen[seen.index(link):]]


def _few(names: list[str], n: int = 6) -> str:
    return ", ".join(repr(name) for name in names[:n]) + (f" and {len(names) - n} more" if len(names) > n else "")


def _elements(root: ET.Element, urdf: object) -> Iterator[tuple[str, ET.Element]]:
    """Every element pybullet reads, with where it is (``link 'name' <tag>``), at most :data:`MAX_DEPTH` deep."""
    for top in root:
        if top.tag in UNREAD or not isinstance(top.tag, str):
            continue
        owner = f"{_tag(top)} {top.get('name')!r}"
        stack = [(top, 1)]
        while stack:
            element, depth = stack.pop()
            if depth > MAX_DEPTH:
                raise ValueError(f"{urdf}: {owner}: elements nested more than {MAX_DEPTH} deep")
            yield f"{owner} <{_tag(element)}>", element
            stack.extend((child, depth + 1) for child in element if isinstance(child.tag, str))


def _tag(element: ET.Element) -> str:
    """The element's tag as the file writes it: ``xacro:macro`` for an element in xacro's namespace."""
    namespace, _, local = element.tag.rpartition("}")
    return f"xacro:{local}" if "xacro" in namespace else element.tag


def _check_element(element: ET.Element, where: str) -> None:
    if _tag(element).startswith("xacro:"):
        raise ValueError(f"{where} is xacro, not URDF: expand the file with xacro first, e.g. xacro "
                         "robot.urdf.xacro > robot.urdf")
    for key, value in element.attrib.items():
        leftover = _XACRO.search(value)
        if leftover:
            raise ValueError(f"{where} {key}={value!r} holds the unexpanded xacro {leftover.group()!r} (pybullet "
                             "would read it as 0): expand the file with xacro first, e.g. xacro robot.urdf.xacro "
                             "> robot.urdf")
    for key, count in NUMBERS.get(element.tag, {}).items():
        text = element.get(key)
        if text is None:
            continue
        values = _finite(text, count)
        if values is None:
            raise ValueError(f"{where} {key}: expected {count} finite number{'s' if count > 1 else ''}, got {text!r}")
        negative = (element.tag == "mass" or (element.tag == "inertia" and key in ("ixx", "iyy", "izz"))) \
            and values[0] < 0.0
        if negative:
            raise ValueError(f"{where} {key}={text!r} is negative; a link's mass and principal moments of inertia "
                             "are >= 0 (pybullet would simulate them as given)")
    if element.tag == "inertial":
        mass = element.find("mass")
        if mass is None or mass.get("value") is None or element.find("inertia") is None:
            raise ValueError(f"{where} needs <mass value=...> and <inertia ...>: give the link's mass and inertia "
                             "(or leave the <inertial> out: the link then weighs a token gram)")


def _finite(text: str, count: int) -> list[float] | None:
    """``text`` as ``count`` finite numbers, or None."""
    tokens = text.split()
    if len(tokens) != count or not all(_NUMBER.fullmatch(token) for token in tokens):
        return None
    values = [float(token) for token in tokens]
    return values if all(math.isfinite(v) for v in values) else None  # 1e999 overflows to inf
