"""ClutterFly-v1 under dynamics='reduced' and 'auto': the choice and its reasons, the model against full physics in
free flight, the hand-over at a contact (no interpenetration, no energy gain), the pose a camera sees, the dynamics
randomisation, the thrust estimate, determinism and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from clutter_gym.datatypes import DynamicsSample
from clutter_gym.sim import GRAVITY

SIZE = (6.0, 6.0, 4.0)
#: the drone hovering in the middle of the empty volume, 2 m from every wall
OPEN = {"scene": {"obstacles": [], "start": [0.0, 0.0, 2.0, 0.0], "goal": [2.0, 2.0, 2.0]}}
#: a slab 0.5 m above it
SLAB_ABOVE = {"scene": {"obstacles": [{"shape": "box", "size": [1.0, 1.0, 0.1], "position": [0.0, 0.0], "z": 2.5}],
                        "start": [0.0, 0.0, 2.0, 0.0], "goal": [2.0, 2.0, 2.0]}}
#: action: full collective thrust, no rates; and the rotors stopped
CLIMB, FALL = np.array([1.0, 0.0, 0.0, 0.0]), np.array([-1.0, 0.0, 0.0, 0.0])


def fly(make_env, mode, **kwargs):
    return make_env("ClutterFly-v1", dynamics=mode, volume_size=SIZE, **kwargs)


def flight(env, actions, options):
    """(centre of mass, linear velocity) after each of ``actions`` from the scene of ``options``."""
    env.reset(seed=0, options=options)
    out = []
    for action in actions:
        env.step(np.asarray(action, dtype=np.float32))
        state = env.unwrapped.dynamics.state()
        com = state.position + state.rotation @ env.unwrapped.robot.mass_properties.com
        out.append(np.concatenate([com, state.linear_velocity]))
    return np.array(out)


@pytest.mark.parametrize(("mode", "model"), [("auto", "reduced"), ("reduced", "reduced"), ("physics", "physics")])
def test_the_reset_says_which_model_runs_and_why(make_env, mode, model):
    env = fly(make_env, mode)
    _, info = env.reset(seed=0)
    assert info["dynamics"]["model"] == model
    assert f"dynamics={mode!r}" in info["dynamics"]["reason"]


@pytest.mark.parametrize("mode", ["fast", None])
def test_an_unknown_mode_is_refused_by_name(make_env, mode):
    with pytest.raises(ValueError, match="dynamics must be one of"):
        fly(make_env, mode)


def test_in_free_flight_the_model_flies_as_full_physics_and_pybullet_is_not_stepped(make_env):
    """Seeded rate commands around the hover for 3 s in the empty volume: every step reduced, and the flight the
    same as pybullet's to a micrometre."""
    env = fly(make_env, "reduced")
    hover = env.unwrapped.robot.hover_action(GRAVITY)
    actions = hover + np.repeat(np.random.default_rng(0).uniform(-0.1, 0.1, (9, 4)), 10, axis=0)
    reduced = flight(env, actions, OPEN)
    full = flight(fly(make_env, "physics"), actions, OPEN)
    assert env.unwrapped.dynamics.reduced_steps == len(actions) and env.unwrapped.dynamics.full_steps == 0
    assert np.abs(full - reduced).max() < 1e-6
    assert np.linalg.norm(full[-1, :3] - full[0, :3]) > 0.1  # it flew somewhere


def test_a_climb_into_a_slab_is_handed_to_full_physics_without_interpenetration_or_energy_gain(make_env):
    """Full thrust at a slab 0.5 m above: the steps far from it run reduced and fly as full physics does, the steps
    that could reach it run under full physics from the model's state, and the drone meets the slab no faster and
    stops against it no deeper than under full physics alone."""
    runs = {}
    for mode in ("physics", "reduced"):
        env = fly(make_env, mode)
        env.reset(seed=0, options=SLAB_ABOVE)
        rows = []
        for _ in range(30):
            _, _, _, _, info = env.step(CLIMB)
            state = env.unwrapped.dynamics.state()
            rows.append((state.position[2], np.linalg.norm(state.linear_velocity), info["min_clearance"],
                         getattr(env.unwrapped.dynamics, "full", True)))
        runs[mode] = np.array(rows)
    dynamics = env.unwrapped.dynamics
    assert dynamics.reduced_steps > 3 and dynamics.full_steps > 3
    first_full = int(np.argmax(runs["reduced"][:, 3]))
    assert np.abs(runs["reduced"][:first_full, :3] - runs["physics"][:first_full, :3]).max() < 1e-9
    assert runs["reduced"][:, 1].max() <= runs["physics"][:, 1].max() + 1e-6
    assert runs["reduced"][:, 2].min() >= min(runs["physics"][:, 2].min(), 0.0) - 1e-4
    assert runs["physics"][:, 2].min() < 1e-3  # it did reach the slab


def test_a_fall_onto_the_floor_gains_no_energy_at_the_hand_over(make_env):
    """Rotors commanded off from a hover 2 m up: the drone falls under the model, is handed to full physics above
    the floor and lands. Thrust only slows the fall, so its energy (kinetic and potential) never exceeds its start's
    at any step, either model."""
    for mode in ("physics", "reduced"):
        env = fly(make_env, mode)
        run = flight(env, [FALL] * 40, OPEN)
        mass = env.unwrapped.robot.mass_properties.mass
        energy = mass * (0.5 * np.sum(run[:, 3:] ** 2, axis=1) + GRAVITY * run[:, 2])
        start = mass * GRAVITY * (2.0 + env.unwrapped.robot.mass_properties.com[2])
        assert energy.max() <= start + 1e-9, mode
        assert run[-1, 2] < 0.2  # it landed
        if mode == "reduced":
            dynamics = env.unwrapped.dynamics
            assert dynamics.reduced_steps > 5 and dynamics.full_steps > 5


def test_the_same_seed_gives_the_same_trajectory(make_env):
    actions = np.random.default_rng(2).uniform(-1, 1, (60, 4))
    a, b = (flight(fly(make_env, "reduced", obstacle_density=0.1), actions, None) for _ in range(2))
    assert np.array_equal(a, b)


def test_a_camera_sees_the_drone_where_the_model_has_it(make_env):
    env = fly(make_env, "reduced", render_mode="rgb_array")
    env.reset(seed=0, options=OPEN)
    hover = env.unwrapped.robot.hover_action(GRAVITY)
    for _ in range(10):
        env.step(hover + np.array([0.05, 0.1, 0.0, 0.2]))
    base = env.unwrapped
    assert base.dynamics.reduced_steps == 10
    state = base.dynamics.state()
    com, rotation, _, _ = base.sim.base_state(base.robot.body)
    assert np.asarray(com) == pytest.approx(state.position + state.rotation @ base.robot.mass_properties.com, abs=1e-9)
    assert np.reshape(rotation, (3, 3)) == pytest.approx(state.rotation, abs=1e-6)
    assert env.render().shape[2] == 3


@pytest.mark.parametrize("sample", [DynamicsSample(motor_scale=0.7), DynamicsSample(mass_scale=1.4)],
                         ids=["motors", "mass"])
def test_the_episode_dynamics_and_the_thrust_estimate_follow_full_physics(make_env, sample):
    """Weaker motors or a heavier airframe: the model flies as pybullet does, and the flight controller's thrust
    estimate (a per-tick filter the model carries) reads the same."""
    runs, ratios = [], []
    for mode in ("physics", "reduced"):
        env = fly(make_env, mode, observe_thrust_ratio=True)
        env.reset(seed=0, options=OPEN)
        env.unwrapped.dynamics.apply_dynamics(sample)
        hover = env.unwrapped.robot.hover_action(GRAVITY)
        for _ in range(20):
            obs, *_ = env.step(hover + np.array([0.3, 0.0, 0.0, 0.0]))
        runs.append(env.unwrapped.dynamics.state().position)
        ratios.append(float(obs["thrust_ratio"][0]))
    assert np.abs(runs[0] - runs[1]).max() < 1e-6
    assert ratios[1] == pytest.approx(ratios[0], abs=1e-9)
    assert ratios[1] < 0.9  # the estimate saw the weaker airframe
