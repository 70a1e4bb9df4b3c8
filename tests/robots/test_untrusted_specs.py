"""A robot spec, its URDF and the cache they are prepared into, read as someone else's files: a name is never a path,
meshes are read only where the user allows and only when they are small regular mesh files, what is cached is
checked on every use, and a YAML spec cannot stand for gigabytes (docs/robots.md, "The cache, names and meshes")."""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import gymnasium as gym
import pybullet_data
import pytest
from helpers import make_refusal, peak_mib, run_capped

from clutter_gym.assets import asset_path
from clutter_gym.collision import acm as acm_module
from clutter_gym.collision.acm import load_acm
from clutter_gym.robots.urdf_prep import prepared_urdf
from clutter_gym.robots.wheeled import wheeled_base_from_spec

DIFFBOT = asset_path("robots/diffbot.urdf")
HUSKY = Path(pybullet_data.getDataPath()) / "husky" / "husky.urdf"
#: a tetrahedron: a mesh pybullet and trimesh load
TETRA = "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
#: a visual-only link, so the mesh is read for the copy and by pybullet, and the collision model stays the diffbot's
DECO = ('<link name="deco{i}"><visual><geometry><mesh filename="{name}"/></geometry></visual></link><joint '
        'name="deco{i}_joint" type="fixed"><parent link="base_link"/><child link="deco{i}"/></joint>')


def spec(urdf, **extra) -> dict:
    return {"kind": "diff_drive", "urdf": str(urdf), "left_wheels": ["left_wheel_joint"],
            "right_wheels": ["right_wheel_joint"], **extra}


def diffbot_with(folder: Path, *meshes: str) -> Path:
    """The diffbot's URDF in ``folder`` with a decoration link per mesh file name."""
    folder.mkdir(parents=True, exist_ok=True)
    links = "".join(DECO.format(i=i, name=name) for i, name in enumerate(meshes))
    urdf = folder / "v.urdf"
    urdf.write_text(DIFFBOT.read_text().replace("</robot>", links + "</robot>"))
    return urdf


def files_under(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file()) if folder.exists() else []


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    return tmp_path / "cache" / "clutter-gym" / "robots"


# -- item 1: the name --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["{tmp}/esc/evil", "../../../../../../../..{tmp}/esc/evil", "a/b", "..", ".hidden",
                                  "x" * 65, "x" * 300, "bad\0name", ["evil"], 3])
def test_a_name_that_is_not_a_plain_file_name_is_refused_and_nothing_is_written(name, tmp_path, cache):
    """On main a name with a separator wrote ``<name>.urdf`` wherever it pointed, and the env worked; 300 characters
    gave a raw OSError, a NUL "embedded null byte", and a list was taken as a name."""
    (tmp_path / "esc").mkdir()
    name = name.format(tmp=tmp_path) if isinstance(name, str) else name
    with pytest.raises(ValueError) as error:
        gym.make("ClutterNav-v1", robot=spec(DIFFBOT, name=name))
    assert str(error.value).startswith("robot: name must be a plain file name: 1 to 64 letters, digits")
    assert "\n" not in str(error.value) and len(str(error.value)) < 300
    assert files_under(tmp_path / "esc") == [] and files_under(cache) == []


def test_a_spec_file_whose_name_is_a_path_is_refused_naming_the_file(tmp_path, cache):
    (tmp_path / "esc").mkdir()
    spec_file = tmp_path / "bot.yaml"
    spec_file.write_text(json.dumps(spec(DIFFBOT, name=str(tmp_path / "esc" / "evil"))))
    with pytest.raises(ValueError, match=rf"^robot spec {spec_file}: name must be a plain file name"):
        gym.make("ClutterNav-v1", robot=str(spec_file))
    assert files_under(tmp_path / "esc") == []


def test_without_a_name_the_urdf_file_name_is_made_plain(tmp_path, cache):
    urdf = tmp_path / "my robot (v2).urdf"
    urdf.write_text(DIFFBOT.read_text())
    base = wheeled_base_from_spec(spec(urdf), "robot")
    assert base.name == "my_robot__v2_" and base.urdf.name == "my_robot__v2_.urdf" and base.urdf.is_relative_to(cache)


# -- item 2: the meshes ------------------------------------------------------------------------------------------

@pytest.fixture
def secret(tmp_path) -> Path:
    """A mesh file of the user's outside the URDF's folder, readable by the user only."""
    path = tmp_path / "private" / "secret.obj"
    path.parent.mkdir()
    path.write_text(TETRA)
    path.chmod(0o600)
    return path


@pytest.mark.parametrize("form", ["file://{secret}", "{secret}", "../private/secret.obj", "package://private/secret.obj",
                                  "link.obj", "file:///proc/self/environ"])
def test_a_mesh_outside_the_urdf_folder_is_refused_before_anything_is_copied(form, tmp_path, cache, secret):
    """On main each of these was copied into the cache (mode 0644) and the env worked: ``package://`` searched every
    parent folder up to ``/``, and a link was followed out. The first mesh, which is allowed, is not copied either."""
    folder = tmp_path / "robot"
    folder.mkdir()
    (folder / "part.obj").write_text(TETRA)
    (folder / "link.obj").symlink_to(secret)
    urdf = diffbot_with(folder, "part.obj", form.format(secret=secret))
    with pytest.raises(ValueError) as error:
        gym.make("ClutterNav-v1", robot=spec(urdf))
    message = str(error.value)
    assert message.startswith(f"robot: the URDF was refused: {urdf}: <mesh filename=") and "\n" not in message
    assert ("outside the URDF's folder" in message or "not found" in message) and "package_roots" in message
    assert files_under(cache) == []


def _sparse(path: Path) -> None:
    path.touch()
    os.truncate(path, 3 << 30)  # 3 GB that take no disk


@pytest.mark.parametrize("name, make, why", [
    ("part.txt", lambda path: path.write_text("s"), "not a mesh file pybullet reads"),
    ("part.obj", os.mkfifo, "not a regular file"),
    ("part.obj", _sparse, "3,221,225,472 bytes: over the 67,108,864"),
])
def test_a_mesh_that_is_no_small_regular_mesh_file_is_refused_without_reading_it(name, make, why, tmp_path):
    """On main a text file was copied and then refused by pybullet, a FIFO was "not found", and a 3 GB (sparse)
    "mesh" was read whole to hash it (a MemoryError here); each runs in a process of its own, capped at 3 GB and
    60 s, and nothing reads the file."""
    folder = tmp_path / "robot"
    folder.mkdir()
    make(folder / name)
    urdf = diffbot_with(folder, name)
    result = make_refusal(spec(urdf), tmp_path / "cache", timeout=60)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.startswith(f"robot: the URDF was refused: {urdf}: <mesh filename='{name}'> is ")
    assert why in result.stdout and result.stdout.count("\n") == 1
    assert peak_mib(result) < 1024 and files_under(tmp_path / "cache") == []


def test_a_package_root_is_read_only_when_the_spec_grants_it_and_copies_keep_their_mode(tmp_path, cache):
    """A ROS layout (``<pkg>/urdf/robot.urdf`` naming ``package://<pkg>/meshes/...``) needs the package granted:
    ``package_roots`` in the spec, relative to the spec file. The copies keep the sources' modes (0644 on main)."""
    package = tmp_path / "my_pkg"
    (package / "meshes").mkdir(parents=True)
    (package / "meshes" / "part.obj").write_text(TETRA)
    (package / "meshes" / "part.obj").chmod(0o600)
    urdf = diffbot_with(package / "urdf", "package://my_pkg/meshes/part.obj")
    spec_file = tmp_path / "bot.yaml"
    spec_file.write_text(json.dumps(spec(urdf.relative_to(tmp_path))))
    with pytest.raises(ValueError, match=r"not found .*needs its folder granted: package_roots: \{my_pkg: ...\}"):
        gym.make("ClutterNav-v1", robot=str(spec_file))
    spec_file.write_text(json.dumps(spec(urdf.relative_to(tmp_path), package_roots={"my_pkg": "my_pkg"})))
    gym.make("ClutterNav-v1", robot=str(spec_file)).close()
    copies = [p for p in files_under(cache) if p.suffix == ".obj"]
    assert len(copies) == 1 and copies[0].read_text() == TETRA and stat.S_IMODE(copies[0].stat().st_mode) == 0o600
    spec_file.write_text(json.dumps(spec(urdf.relative_to(tmp_path), package_roots={"my_pkg": "nowhere"})))
    with pytest.raises(ValueError, match=rf"^robot spec {spec_file}: package_roots.my_pkg must be a folder"):
        gym.make("ClutterNav-v1", robot=str(spec_file))


# -- item 11: the cache, checked on every use -------------------------------------------------------------------

@pytest.mark.parametrize("spoil", [
    lambda urdf, mesh: urdf.write_text(urdf.read_text().replace("33.455", "0.001")),  # an edited URDF
    lambda urdf, mesh: urdf.write_text(urdf.read_text()[:500]),  # a URDF cut short
    lambda urdf, mesh: mesh.write_bytes(mesh.read_bytes()[:100]),  # a mesh cut short
    lambda urdf, mesh: mesh.unlink(),
    lambda urdf, mesh: (mesh.unlink(), mesh.symlink_to("/dev/zero")),
])
def test_a_cached_copy_that_was_changed_is_prepared_again(spoil, cache):
    """On main the copy was keyed by the source's digest and never read back: an edited copy was used as it was,
    and one cut short failed every make until deleted by hand."""
    first = prepared_urdf(HUSKY, "husky")
    text, mesh = first.read_text(), first.parent / "meshes" / "wheel.stl"
    spoil(first, mesh)
    assert prepared_urdf(HUSKY, "husky") == first
    assert first.read_text() == text and not mesh.is_symlink()
    assert mesh.read_bytes() == (HUSKY.parent / "meshes" / "wheel.stl").read_bytes()


def test_a_corrupt_cached_acm_is_generated_again(tmp_path, cache, monkeypatch):
    """On main a cached ACM cut short gave a raw JSONDecodeError on every later make."""
    monkeypatch.setattr(acm_module, "SHIPPED_DIR", tmp_path / "none")
    urdf = prepared_urdf(DIFFBOT, "diffbot")
    first = load_acm(urdf, "sphere", samples=50)
    (cached,) = (tmp_path / "cache" / "clutter-gym" / "acm").glob("*.json")
    for corrupt in (cached.read_text()[:40], "[]", json.dumps({**json.loads(cached.read_text()), "links": [[1]]})):
        cached.write_text(corrupt)
        assert load_acm(urdf, "sphere", samples=50) == first
        assert json.loads(cached.read_text())["key"] == first.key


def test_an_unwritable_cache_falls_back_to_a_temporary_folder_and_says_so_once(tmp_path):
    """A file where the cache should be cannot be written, even by root (who writes through a read-only mode): on
    main ``robot="husky"`` failed with a raw OSError. Two makes in one process: one warning."""
    blocker = tmp_path / "cache"
    blocker.write_text("not a folder")
    code = ("import warnings, gymnasium as gym, clutter_gym\n"
            "warnings.simplefilter('always')\n"
            "for _ in range(2):\n"
            "    gym.make('ClutterNav-v1', robot='husky').close()\n")
    result = run_capped(code, timeout=300, env={**os.environ, "XDG_CACHE_HOME": str(blocker)})
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stderr.count("RuntimeWarning: clutter-gym cannot use its cache") == 1, result.stderr
    assert blocker.read_text() == "not a folder"


def test_a_yaml_spec_of_nested_aliases_is_refused_in_bounded_memory(tmp_path):
    """524 bytes of aliases of aliases stand for 9^9 strings: on main the make ran into a MemoryError (at 6.4 GB under
    an 8 GB cap)."""
    items = ['&a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    items += [f"&a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 9)]
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text(f"kind: diff_drive\nurdf: {DIFFBOT}\nleft_wheels: [left_wheel_joint]\n"
                    f"right_wheels: [right_wheel_joint]\nwheel_radius: [{', '.join(items)}]\n")
    result = make_refusal(str(bomb), tmp_path / "cache")
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout == (f"robot spec file {bomb} stands for more than 1,048,576 nodes and characters with its "
                             "aliases expanded (aliases of aliases multiply)\n")
    assert peak_mib(result) < 1024


def test_a_bad_value_is_shown_cut_short(cache):
    """On main the message held the whole value's repr."""
    with pytest.raises(ValueError) as error:
        wheeled_base_from_spec(spec(DIFFBOT, wheel_radius=list(range(100_000))), "robot")
    assert str(error.value) == "robot: wheel_radius must be a number in [0.005, 2], got [0, 1, 2, 3, 4, 5, ...]"
