"""The run folder: one place per training run, laid out so a reader (or a resumed run) finds everything.

```
RUN/
  config.yaml            the resolved TrainConfig
  episodes.csv           one row per finished training episode (timestep + EpisodeStats fields)
  tb/                    TensorBoard event files
  checkpoints/step_<N>/  model.zip + vecnormalize.pkl, every ``checkpoint_every`` steps (newest few kept)
  model/                 the final model.zip + vecnormalize.pkl
  eval.json              the evaluation after training
```

A checkpoint is written into a temporary folder and renamed into place, so every ``step_<N>`` folder is
complete; a run killed mid-write leaves only a hidden temporary folder, which the next save removes.
"""

from __future__ import annotations

import csv
import re
import shutil
from pathlib import Path
from typing import Any

import yaml

from clutter_gym.atomic import atomic_folder, atomic_path, write_text_atomically
from clutter_gym.training.config import TrainConfig

MODEL_FILE = "model.zip"
NORMALIZER_FILE = "vecnormalize.pkl"
_STEP_DIR = re.compile(r"^step_(\d+)$")


class RunDir:
    """Paths and reads/writes of one run folder (see the module docstring for the layout)."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.config_file = self.root / "config.yaml"
        self.episodes_file = self.root / "episodes.csv"
        self.tb_dir = self.root / "tb"
        self.checkpoints_dir = self.root / "checkpoints"
        self.model_dir = self.root / "model"
        self.eval_file = self.root / "eval.json"

    # -- config ---------------------------------------------------------------------------------------------
    def write_config(self, config: TrainConfig) -> None:
        write_text_atomically(self.config_file, yaml.safe_dump(config.to_dict(), sort_keys=False))

    def read_config(self) -> TrainConfig:
        if not self.config_file.is_file():
            raise FileNotFoundError(f"{self.root} is not a run folder: it has no config.yaml")
        return TrainConfig.from_dict(yaml.safe_load(self.config_file.read_text()))

    # -- checkpoints ----------------------------------------------------------------------------------------
    def checkpoints(self) -> list[tuple[int, Path]]:
        """Complete checkpoints as (step, folder), oldest first."""
        if not self.checkpoints_dir.is_dir():
            return []
        found = []
        for child in self.checkpoints_dir.iterdir():
            match = _STEP_DIR.match(child.name)
            if match and (child / MODEL_FILE).is_file():
                found.append((int(match.group(1)), child))
        return sorted(found)

    def latest_checkpoint(self) -> tuple[int, Path] | None:
        found = self.checkpoints()
        return found[-1] if found else None

    def save_checkpoint(self, model: Any, normalizer: Any | None, step: int, keep: int) -> Path:
        """Write ``checkpoints/step_<step>`` atomically, then delete all but the newest ``keep`` checkpoints."""
        target = self.checkpoints_dir / f"step_{step:010d}"
        self.save_model(model, normalizer, target)
        for stale in self.checkpoints_dir.glob(".step_*"):  # temporary folders of an earlier killed write
            shutil.rmtree(stale, ignore_errors=True)
        for _, folder in self.checkpoints()[:-keep]:
            shutil.rmtree(folder, ignore_errors=True)
        return target

    @staticmethod
    def save_model(model: Any, normalizer: Any | None, folder: Path) -> None:
        """SB3 model (and VecNormalize statistics, if any) into ``folder``, which appears complete or not at all."""
        with atomic_folder(folder) as tmp:
            model.save(tmp / MODEL_FILE)
            if normalizer is not None:
                normalizer.save(tmp / NORMALIZER_FILE)

    def policy_folder(self) -> Path:
        """The final model if training finished, else the newest checkpoint."""
        if (self.model_dir / MODEL_FILE).is_file():
            return self.model_dir
        latest = self.latest_checkpoint()
        if latest is None:
            raise FileNotFoundError(f"{self.root} holds no model and no checkpoint yet")
        return latest[1]

    def is_finished(self) -> bool:
        return (self.model_dir / MODEL_FILE).is_file()

    # -- episode log ----------------------------------------------------------------------------------------
    def read_episodes(self) -> list[dict[str, float]]:
        if not self.episodes_file.is_file():
            return []
        with self.episodes_file.open(newline="") as f:
            return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]

    def truncate_episodes(self, last_step: int) -> None:
        """Drop episode rows logged after ``last_step`` (the steps a resumed run will redo)."""
        rows = [row for row in self.read_episodes() if row["timestep"] <= last_step]
        with atomic_path(self.episodes_file) as tmp, tmp.open("w", newline="") as f:
            if rows:
                writer = csv.DictWriter(f, fieldnames=list(rows[0]))
                writer.writeheader()
                writer.writerows(rows)
