"""Ctrl-C during training: a checkpoint is written at once, one line says at which step and how to resume, the exit
status is 130, no traceback (issue 53.4).

Each run is a subprocess in a session of its own, and the interrupt goes to its whole process group, as a terminal's
Ctrl-C does: the env worker processes get it too. The budgets are large and the interrupt comes once the first
training episode is logged, so it lands mid-training; a timeout ends a run that hangs.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import yaml

from clutter_gym.training.policy_file import saved_step
from clutter_gym.training.run_dir import MODEL_FILE, RunDir

REPO = Path(__file__).resolve().parents[2]
CLI = Path(sys.executable).with_name("clutter-gym")
#: Two envs (stepped by this process and one worker process), short rollouts, no checkpoint or validation on schedule.
SMALL = ["--n-envs", "2", "--checkpoint-every", "100000", "--final-eval-episodes", "0", "--n-steps", "64",
         "--batch-size", "64", "--n-epochs", "1", "--no-progress"]


def interrupt_once_training(command: list, run: Path, timeout: float = 300) -> tuple[int, str]:
    """Start ``command``, send SIGINT to its process group once ``run`` has logged a training episode; its exit
    status and its stdout and stderr together."""
    # A shell's background job (`cmd &`, nohup) starts with SIGINT ignored, which its children inherit and Python
    # keeps: the run would never see the Ctrl-C. A terminal's foreground job, which this imitates, does not ignore it.
    proc = subprocess.Popen([str(a) for a in command], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + timeout
        while not RunDir(run).read_episodes():
            assert proc.poll() is None, f"ended before training: {proc.communicate()}"
            assert time.monotonic() < deadline, "no training episode logged in time"
            time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    return proc.returncode, out + err


def test_ctrl_c_in_train_writes_a_checkpoint_and_the_run_resumes_from_it(tmp_path):
    out = tmp_path / "run"
    status, text = interrupt_once_training([CLI, "train", "--timesteps", "100000", *SMALL, "--out", out], out)
    assert status == 130 and "Traceback" not in text, text
    said = re.search(rf"interrupted at step (\d+); run clutter-gym train --resume {re.escape(str(out))} to resume",
                     text)
    assert said, text
    step = int(said[1])
    assert RunDir(out).checkpoints()[-1][0] == step > 0
    resumed = subprocess.run([str(CLI), "train", "--resume", str(out), "--timesteps", str(step + 128), "--no-progress"],
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"continuing from the checkpoint of step {step}" in resumed.stderr
    assert saved_step(out / "model" / MODEL_FILE) == step + 128  # two rollouts of 64 steps x 2 envs after it


def test_ctrl_c_in_the_main_job_through_tasks_py_says_to_run_it_again(tmp_path):
    """``python3 tasks.py main``: tasks.py waits for the job to write its checkpoint and prints nothing of its own."""
    settings = tmp_path / "small.yml"
    settings.write_text(yaml.safe_dump({"ClutterNav-v1": {
        "n_envs": 2, "checkpoint_every": 100000, "ppo": {"n_steps": 64, "batch_size": 64, "n_epochs": 1}}}))
    out = tmp_path / "main"
    status, text = interrupt_once_training([sys.executable, REPO / "tasks.py", "main", "--timesteps", "100000",
                                            "--out", out, "--hyperparams", settings, "--no-progress"], out / "run")
    assert status == 130 and "Traceback" not in text, text
    said = re.search(r"clutter-gym report: interrupted at step (\d+); run the same command again to resume", text)
    assert said, text
    assert RunDir(out / "run").checkpoints()[-1][0] == int(said[1])
