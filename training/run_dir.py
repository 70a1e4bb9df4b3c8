"""The run folder: one place per training run, laid out so a reader (or a resumed run) finds everything.

```
RUN/
  config.yaml            the resolved TrainConfig, the run format and the package versions that wrote it
  episodes.csv           one row per finished training episode (timestep + EpisodeStats fields)
  tb/                    TensorBoard event files
  checkpoints/step_<N>/  model.zip + vecnormalize.npz, after the first rollout and every ``checkpoint_every`` steps
                         (newest few kept)
  model/                 the final model.zip + vecnormalize.npz
  best/                  the policy that did best in the validations during training (when they are on)
  validation.csv         one row per validation: step, success and collision rates, whether it became best/
  distill.csv            one row per DAgger round of a run with a teacher: its steps, samples, teacher share,
                         fit loss, rollout and validation rates, wall time
  training.json          wall time spent in training (summed over resumes) and the steps reached
  eval.json              the evaluation after training
```

A checkpoint is written into a temporary folder and renamed into place, so every ``step_<N>`` folder is
complete; a run killed mid-write leaves only a hidden temporary folder, which the next save removes. The episode
log is appended row by row, so a kill can leave its last row torn: reading drops that row.
"""

from __future__ import annotations

import csv
import io
import json
import os
import platform
import re
import shutil
import subprocess
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from importlib import metadata
from pathlib import Path
from typing import Any

import yaml

from clutter_gym import RENAMED_IDS
from clutter_gym.training.config import TrainConfig
from clutter_gym.training.normalizer import NORMALIZER_FILE, save_normalizer
from clutter_gym.util.atomic import atomic_folder, atomic_path, write_text_atomically
from clutter_gym.util.safe_yaml import read_yaml

MODEL_FILE = "model.zip"
_STEP_DIR = re.compile(r"^step_(\d+)$")
#: Layout version of a run folder. A config.yaml without one predates the field and has format 1.
RUN_FORMAT = 1
_PACKAGES = ("clutter-gym", "stable-baselines3", "torch", "gymnasium", "numpy")


class IncompatibleRunError(ValueError):
    """A run folder that this version of clutter-gym cannot rebuild (another format, settings or model file)."""


class RunWriteError(OSError):
    """A model folder that could not be written (a full disk, say); the message names it and the free space."""


@contextmanager
def writing(path: Path) -> Iterator[None]:
    """Turn a failed write of ``path`` (a full disk, a file size limit) into a :class:`RunWriteError` that names it
    and the free space there."""
    try:
        yield
    except OSError as exc:
        if isinstance(exc, RunWriteError):
            raise
        free = shutil.disk_usage(path.parent).free / 2**20
        raise RunWriteError(f"could not write {path}: {exc.strerror or exc} ({free:,.0f} MiB free there); what was "
                            "saved before is kept") from None


def package_versions() -> dict[str, str]:
    """Versions of the packages a run's files depend on, Python's, and the clutter-gym commit when the run is
    started from a git checkout of clutter-gym (see :func:`checkout_commit`)."""
    versions = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    commit = checkout_commit(Path.cwd())
    return {**versions, "python": platform.python_version(), **({"clutter-gym commit": commit} if commit else {})}


def checkout_commit(folder: Path) -> str | None:
    """The commit of the clutter-gym git checkout ``folder`` lies in (``python3 tasks.py`` runs there), with
    ``-dirty`` when its tracked files have uncommitted changes; None outside such a checkout or without git."""
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True, timeout=10,
                              check=True).stdout.strip()

    try:
        root = Path(git("rev-parse", "--show-toplevel"))
        if 'name = "clutter-gym"' not in (root / "pyproject.toml").read_text():
            return None
        commit = git("rev-parse", "HEAD")
        dirty = bool(git("status", "--porcelain", "--untracked-files=no"))
    except (OSError, subprocess.SubprocessError):
        return None
    return f"{commit}-dirty" if dirty else commit


class RunDir:
    """Paths and reads/writes of one run folder (see the module docstring for the layout)."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.config_file = self.root / "config.yaml"
        self.episodes_file = self.root / "episodes.csv"
        self.tb_dir = self.root / "tb"
        self.checkpoints_dir = self.root / "checkpoints"
        self.model_dir = self.root / "model"
        self.best_dir = self.root / "best"
        self.validation_file = self.root / "validation.csv"
        self.eval_file = self.root / "eval.json"
        self.training_file = self.root / "training.json"
        self.distill_file = self.root / "distill.csv"

    # -- config ---------------------------------------------------------------------------------------------
    def write_config(self, config: TrainConfig) -> None:
        data = {"run_format": RUN_FORMAT, "written_by": package_versions(), **config.to_dict()}
        write_text_atomically(self.config_file, yaml.safe_dump(data, sort_keys=False))

    def written_by(self) -> dict[str, str]:
        """The package versions recorded when the config was last written (empty for runs that predate them)."""
        return dict(self._read_config_file().get("written_by") or {})

    def read_config(self) -> TrainConfig:
        """The run's config.

        Raises:
            FileNotFoundError: the folder holds no run.
            IncompatibleRunError: the run's format or settings do not fit this version of clutter-gym.
        """
        data = self._read_config_file()
        run_format, written_by = data.pop("run_format", 1), data.pop("written_by", None) or {}
        wrote = f"clutter-gym {written_by.get('clutter-gym', '0.1.0 or older')}"
        here = f"clutter-gym {package_versions()['clutter-gym']}"
        if run_format != RUN_FORMAT:
            raise IncompatibleRunError(f"{self.root} is a run of format {run_format!r}, written by {wrote}; this "
                                       f"{here} reads format {RUN_FORMAT}: use the version that wrote it")
        if data.get("env_id") in RENAMED_IDS:
            new_id = RENAMED_IDS[data["env_id"]]
            warnings.warn(f"{self.root} was trained on {data['env_id']}, which {here} no longer has: it is read as "
                          f"{new_id}, whose defaults changed in 0.3.0 (CHANGELOG.md); retrain it for that env's "
                          "results", UserWarning, stacklevel=2)
            data["env_id"] = new_id
        try:
            return TrainConfig.from_dict(data)
        except (TypeError, ValueError) as exc:
            raise IncompatibleRunError(f"{self.config_file} (written by {wrote}) does not fit {here}: {exc}") from None

    def _read_config_file(self) -> dict:
        if not self.config_file.is_file():
            raise FileNotFoundError(f"{self.root} is not a run folder: it has no config.yaml")
        try:
            data = read_yaml(self.config_file)
        except ValueError as exc:
            raise IncompatibleRunError(str(exc)) from None
        if not isinstance(data, dict):
            raise IncompatibleRunError(f"{self.config_file} is not a mapping of settings")
        return data

    def check_own_files(self) -> None:
        """Refuse a run folder whose entries are symbolic links: training writes into ``tb/``, ``checkpoints/`` and
        the logs, and a link (in a run folder from someone else) would carry those writes out of the folder.

        Raises:
            IncompatibleRunError: naming the link and where it points.
        """
        for path in (self.config_file, self.episodes_file, self.tb_dir, self.checkpoints_dir, self.model_dir,
                     self.best_dir, self.validation_file, self.eval_file, self.training_file):
            if path.is_symlink():
                raise IncompatibleRunError(f"{path} is a symbolic link (to {os.readlink(path)}); training writes "
                                           "there, so a run folder's files must be its own")

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
        """SB3 model (and VecNormalize statistics, if any) into ``folder``, which appears complete or not at all.

        Raises:
            RunWriteError: the folder could not be written; what was there before is kept.
        """
        with writing(folder), atomic_folder(folder) as tmp:
            model.save(tmp / MODEL_FILE)
            if normalizer is not None:
                save_normalizer(normalizer, tmp / NORMALIZER_FILE)

    def policy_folder(self) -> Path:
        """The best validated policy if there is one, else the final model if training finished, else the newest
        checkpoint."""
        for folder in (self.best_dir, self.model_dir):
            if (folder / MODEL_FILE).is_file():
                return folder
        latest = self.latest_checkpoint()
        if latest is None:
            raise FileNotFoundError(f"{self.root} holds no model and no checkpoint yet")
        return latest[1]

    def is_finished(self) -> bool:
        return (self.model_dir / MODEL_FILE).is_file()

    def training_time(self) -> dict[str, float]:
        """``{"seconds": wall time in training, "steps": steps reached}`` (zeros before any training)."""
        if not self.training_file.is_file():
            return {"seconds": 0.0, "steps": 0.0}
        return json.loads(self.training_file.read_text())

    def add_training_time(self, seconds: float, steps: int) -> None:
        total = self.training_time()["seconds"] + seconds
        write_text_atomically(self.training_file, json.dumps({"seconds": total, "steps": float(steps)}))

    # -- validation log -------------------------------------------------------------------------------------
    def read_validations(self) -> list[dict[str, float]]:
        return _read_rows(self.validation_file)

    def append_validation(self, row: dict[str, float]) -> None:
        """Add one validation row (the whole file is rewritten atomically: it holds a few dozen rows)."""
        _write_rows(self.validation_file, [*self.read_validations(), row])

    def truncate_validations(self, last_step: int) -> bool:
        """Drop validation rows after ``last_step`` (the steps a resumed run will redo). When one of them had saved
        ``best/``, that policy belongs to the dropped steps: ``best/`` is removed, the kept rows lose their best
        mark (the next validation sets a new best) and True is returned."""
        rows = self.read_validations()
        kept = [row for row in rows if row["step"] <= last_step]
        dropped_best = any(row["best"] for row in rows if row["step"] > last_step)
        if dropped_best:
            shutil.rmtree(self.best_dir, ignore_errors=True)
            kept = [{**row, "best": 0.0} for row in kept]
        if len(kept) < len(rows):
            _write_rows(self.validation_file, kept)
        return dropped_best

    # -- distillation log -----------------------------------------------------------------------------------
    def read_distill_rows(self) -> list[dict[str, float]]:
        """One row per DAgger round done (:mod:`clutter_gym.training.distill`)."""
        return _read_rows(self.distill_file)

    def append_distill_row(self, row: dict[str, float]) -> None:
        _write_rows(self.distill_file, [*self.read_distill_rows(), row])

    def truncate_distill_rows(self, last_step: int) -> None:
        """Drop the rounds that ended after ``last_step`` (a resumed run redoes them)."""
        rows = self.read_distill_rows()
        kept = [row for row in rows if row["step"] <= last_step]
        if len(kept) < len(rows):
            _write_rows(self.distill_file, kept)

    # -- episode log ----------------------------------------------------------------------------------------
    def read_episodes(self) -> list[dict[str, float]]:
        return _read_rows(self.episodes_file)

    def truncate_episodes(self, last_step: int) -> int:
        """Drop episode rows logged after ``last_step`` (the steps a resumed run will redo) and a torn last row;
        returns how many complete rows were dropped."""
        rows = self.read_episodes()
        kept = [row for row in rows if row["timestep"] <= last_step]
        _write_rows(self.episodes_file, kept)
        return len(rows) - len(kept)


def _read_rows(path: Path) -> list[dict[str, float]]:
    """The rows of a CSV log of numbers; a last row without its line end (torn by a kill or a full disk) is dropped.

    Raises:
        ValueError: a complete row that does not hold one number per column.
    """
    if not path.is_file():
        return []
    text = path.read_text()
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    rows = []
    for line, row in enumerate(csv.DictReader(io.StringIO(text, newline="")), start=2):
        try:
            rows.append({k: float(v) for k, v in row.items()})
        except (TypeError, ValueError):  # a short row gives None, a long one a list under the key None
            raise ValueError(f"{path} line {line} is not a row of {len(row)} numbers: {row}") from None
    return rows


def _write_rows(path: Path, rows: list[dict[str, float]]) -> None:
    with atomic_path(path) as tmp, tmp.open("w", newline="") as f:
        if rows:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
