"""Step stages (clutter_gym.stages): an env has only the stages its settings ask for, its step calls only the hooks
of those active in the episode, and the hooks run in the documented order."""

from __future__ import annotations

import numpy as np

from benchmarks.hard_cases.scenes.large_scenes import ARENA, grid_scene
from clutter_gym import stages as st

SMALL = {"arena_size": 3.0, "n_rays": 16, "sensors": ["lidar"]}


def _kinds(env):
    return [type(stage) for stage in env.unwrapped.stages]


def test_an_env_has_only_the_stages_its_settings_ask_for(make_env):
    """st.Movables and the near field are there whenever the scene may need them, and active only in an episode
    that does (the next test); an env that draws keeps every obstacle a body, so it has no near field."""
    assert _kinds(make_env("ClutterNav-v1", **SMALL)) == [st.AutoPhysics, st.Movables, st.NearField]
    monitored = make_env("ClutterNav-v1", **SMALL, physics="fixed", noise="nominal", reverse=False,
                         safety_horizon=0.3)
    assert _kinds(monitored) == [st.ForwardOnly, st.SafetyMonitor, st.ActionNoiseStage, st.Movables, st.NearField]
    drawn = make_env("ClutterNav-v1", **SMALL, physics="fixed", render_mode="rgb_array")
    assert _kinds(drawn) == [st.Movables, st.RenderTrail]


def test_a_step_calls_only_the_hooks_of_the_stages_active_in_its_episode(make_env):
    plain = make_env("ClutterNav-v1", **SMALL).unwrapped
    plain.reset(seed=0)
    assert plain._command_hooks == plain._actuate_hooks == plain._physics_hooks == plain._checked_hooks == ()
    pushed = make_env("ClutterNav-v1", **SMALL, movable_obstacles=1.0).unwrapped
    pushed.reset(seed=0)
    assert pushed.movable_bodies and len(pushed._physics_hooks) == 1  # the scene has movables: the checker follows
    large = make_env("ClutterNav-v1", arena_size=ARENA, sensors=["lidar"]).unwrapped
    large.reset(seed=0, options={"scene": grid_scene(1000)})
    assert large.arena.near_field_engaged and len(large._checked_hooks) == 1  # the near field follows the robot


class Recorder(st.Stage):
    def __init__(self):
        self.calls = []

    def scene_chosen(self, scene):
        self.calls.append("scene_chosen")

    def episode_start(self, obstacles, bodies, rng):
        self.calls.append("episode_start")
        return True

    def command(self, action):
        self.calls.append("command")
        return action

    def actuate(self, command, rng):
        self.calls.append("actuate")
        return command

    def physics_done(self):
        self.calls.append("physics_done")

    def checked(self, state):
        self.calls.append("checked")

    def step_info(self, info):
        self.calls.append("step_info")
        info["recorded"] = True


def test_hooks_run_in_the_documented_order_and_a_stage_that_overrides_none_is_never_called(make_env):
    env = make_env("ClutterNav-v1", **SMALL).unwrapped
    recorder = Recorder()
    env.stages.append(recorder)
    recorder.bind(env)
    env.reset(seed=1)
    *_, info = env.step(np.zeros(2))
    assert recorder.calls == ["scene_chosen", "episode_start", "checked",
                              "command", "actuate", "physics_done", "checked", "step_info"]
    assert info["recorded"]
    assert st.hooks([st.Stage(), recorder], "command") == (recorder.command,)


def test_the_monitor_stage_reads_the_scan_its_sensor_delivered_last(make_env):
    env = make_env("ClutterNav-v1", **SMALL, safety_horizon=0.3, noise="nominal").unwrapped
    monitor = next(s for s in env.stages if isinstance(s, st.SafetyMonitor))
    seen, run = [], monitor.safety.filter
    monitor.safety.filter = lambda command, scan: seen.append(scan) or run(command, scan)
    env.reset(seed=2)
    for _ in range(3):
        delivered = env.timed_sensors.readings[0]
        *_, info = env.step(np.array([1.0, 0.0]))
        assert seen[-1] is delivered and "safety_scale" in info


def test_stages_hold_no_reference_cycle_through_the_env():
    """A stage that reads the env keeps a weak proxy of it: an env dropped without close() is freed by its reference
    count at once, its physics server with it, not whenever the cyclic collector next runs."""
    import gc
    import weakref

    import gymnasium as gym
    import pybullet as pb

    for kwargs in ({}, {"render_mode": "rgb_array", "safety_horizon": 0.3, "noise": "nominal", "reverse": False}):
        env = gym.make("ClutterNav-v1", **SMALL, **kwargs)
        env.reset(seed=0)
        unwrapped, sim = weakref.ref(env.unwrapped), weakref.ref(env.unwrapped.sim)
        client = env.unwrapped.sim.client_id
        gc.disable()  # only reference counting may free it
        try:
            del env
            assert unwrapped() is None and sim() is None, kwargs  # the Sim's parts hold its record, not the Sim
            assert not pb.isConnected(physicsClientId=client)
        finally:
            gc.enable()
