"""The typed values of one evaluation task: what crosses the executor
boundary (:class:`EvaluationTask` in, :class:`TaskResult` out) and what the
camera chain measures of a task in between (:class:`TaskEvaluation`).

A walk of a task: :func:`.tasks.evaluate_task` (the executor boundary) hands
the task to :meth:`.chain.CameraChain.run`, which evaluates all of it (the
ideal image and its rows, the spectra and read-out in effect, every
realisation, demosaic and metric) and returns a :class:`TaskEvaluation`;
the worker writes the details it keeps and returns
:meth:`TaskEvaluation.result`, the tidy rows.

Seeds: the noise seed of a realisation comes from the study seed, the scene,
the luminance and the realisation's index (:func:`realisation_seeds`), never
from the order in which tasks run nor from the CFA, so realisation k of every
CFA pairs (study/intervals.py).
"""

from __future__ import annotations

__all__ = ["EvaluationTask", "TaskResult", "CameraOutput", "TaskEvaluation", "task_seed", "realisation_seeds"]

import dataclasses
import hashlib
import json
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class EvaluationTask:
    """One (scene, condition, CFA) of a study: what :func:`.tasks.evaluate_task` runs.

    Attributes
    ----------
    source : the render it evaluates (:func:`.tasks.load_scene_image`: a
        cached render's scene and settings, or an EXR path).
    scene : the scene's name (metrics.csv's ``scene``).
    condition : the :class:`~.conditions.Condition`; its ``seed`` is the
        study seed, from which every realisation's noise seed is derived
        (:func:`realisation_seeds`: the one seed path).
    cfa, cfa_label : the CFA (a name or TOML path) and its label in tables.
    demosaics, metrics : what to process and measure.
    chain : the :class:`~.chain.ChainSettings` (one per study, shared).
    details_dir, details_tag : where the first realisation's curves and
        thumbnails go (None: nowhere) and their file stem.
    realisations : noise realisations of the capture (rows carry
        ``realisation`` offset, offset + 1, ...).
    realisation_offset : the index of the task's first realisation (``r S``
        for render seed r of a path-traced scene with S sensor seeds).
    render_seed : the render seed index of the task's render (rows carry it
        as ``render_seed``; 0 for a scene rendered once).
    ideal_rows : also measure the ideal sensor against itself.
    base : the condition is one of the study's own (scored), not a sweep's.
    image_store : the study's folder of optical images, shared by its
        workers (:mod:`.image_store`; None: each worker makes its own).
    """

    source: dict[str, object]
    scene: str
    condition: object
    cfa: str
    demosaics: tuple[str, ...]
    metrics: tuple[str, ...]
    chain: object = None
    cfa_label: str | None = None
    details_dir: str | None = None
    details_tag: str | None = None
    realisations: int = 1
    ideal_rows: bool = False
    base: bool = True
    realisation_offset: int = 0
    image_store: str | None = None
    render_seed: int = 0

    @classmethod
    def of(cls, task) -> "EvaluationTask":
        """A task from an :class:`EvaluationTask` or a dict of its fields."""
        if isinstance(task, cls):
            return task
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(task) - names
        if unknown:
            raise TypeError(f"EvaluationTask has no field(s) {sorted(unknown)}")
        return cls(**{**task, "demosaics": tuple(task["demosaics"]), "metrics": tuple(task["metrics"])})

    def identity(self) -> dict:
        """Everything that determines the task's rows (not where its details
        or its study's optical images go)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name not in ("details_dir", "image_store")}

    @property
    def label(self) -> str:
        """The CFA's label in the tables (its name, or the TOML's)."""
        return self.cfa_label or self.cfa

    @property
    def keeps_details(self) -> bool:
        """Whether the task keeps its first realisation's curves and images
        (only the task that holds a value's first realisation)."""
        return self.details_dir is not None and self.realisation_offset == 0


@dataclass
class TaskResult:
    """What an evaluation task returns through the executor (and what a
    study saves under ``.work/`` to resume): plain rows, JSON-able.

    rows : metrics.csv's realisation rows (scene, cfa, demosaic, the
        condition's columns, spectra, base, realisation, render_seed,
        metric, value, unit, censored and the capture's columns).
    failures : a metric that could not be measured on one camera output
        (the same keys as a row, with ``error`` for the value).
    ideal_rows : the ideal sensor against itself (the 'ideal' range policy's anchor).
    timing : seconds per stage in the worker (optics, capture, process, metrics).
    """

    rows: list = field(default_factory=list)
    failures: list = field(default_factory=list)
    ideal_rows: list = field(default_factory=list)
    timing: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"rows": self.rows, "timing": self.timing, "failures": self.failures, "ideal_rows": self.ideal_rows}

    @classmethod
    def from_dict(cls, data: dict) -> "TaskResult":
        """A result read back (a resume file, checked by :func:`.resume.valid_result`)."""
        return cls(list(data["rows"]), list(data.get("failures", [])), list(data.get("ideal_rows", [])),
                   dict(data["timing"]))


@dataclass
class CameraOutput:
    """One camera output of a task: a realisation processed by one demosaic
    and measured.

    demosaic, realisation, seed : which output (``seed`` its capture's noise seed).
    capture : metrics.csv's columns of the capture (exposure, gains, clipped share).
    rows : its metric rows (``metrics.result_rows``: metric, value, unit, censored).
    failures : ``{metric, error}`` of each metric it could not measure (every
        metric, when the output itself could not be made or mean-matched).
    kept : the :class:`~.chain.Evaluation` (processed image, metric results
        with their curves and maps) and the raw capture of an output whose
        details the task keeps, else None.
    """

    demosaic: str
    realisation: int
    seed: int
    capture: dict
    rows: list
    failures: list
    kept: Any = None
    raw: Any = None


@dataclass
class TaskEvaluation:
    """What :meth:`.chain.CameraChain.run` measured of one task.

    columns : the condition's axes as metrics.csv columns, at the values in
        effect (an axis left to the scene, the f-number, read from the
        ideal image's meta); None when nothing was evaluated.
    spectra : the spectra set the captures used.
    outputs : every :class:`CameraOutput`, realisation by realisation.
    ideal_rows : the ideal against itself (metric rows), when the task asks.
    ideal : the ideal image (None when nothing was evaluated).
    ideal_results : its results for the metrics whose records keep the
        ideal's curves, when asked (details), else None.
    timing : seconds per stage.
    """

    task: EvaluationTask
    columns: dict | None
    spectra: str
    outputs: list
    ideal_rows: list
    ideal: Any = None
    ideal_results: dict | None = None
    timing: dict = field(default_factory=dict)

    def result(self) -> TaskResult:
        """The task's tidy rows (:class:`TaskResult`), one column per condition axis."""
        t = self.task
        rows, failures = [], []
        for out in self.outputs:
            base = {"scene": t.scene, "cfa": t.label, "demosaic": out.demosaic, **self.columns,
                    "spectra": self.spectra, "base": bool(t.base), "realisation": out.realisation,
                    "render_seed": int(t.render_seed)}
            rows.extend({**base, **r, **out.capture} for r in out.rows)
            failures.extend({**base, **f} for f in out.failures)
        ideal = []
        if self.ideal_rows:
            base = {"scene": t.scene, "cfa": "ideal", "demosaic": "none", **self.columns, "base": bool(t.base),
                    "realisation": 0, "render_seed": 0}
            ideal = [{**base, **r} for r in self.ideal_rows]
        return TaskResult(rows, failures, ideal, dict(self.timing))


def task_seed(study_seed: int, *parts) -> int:
    """A noise seed from the study seed and a task's identity (32 bits)."""
    text = json.dumps([int(study_seed), *[str(p) for p in parts]])
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:4], "little")


def realisation_seeds(study_seed: int, scene: str, luminance: float, n: int, offset: int = 0) -> list[int]:
    """The sensor-noise seeds of realisations ``offset .. offset + n - 1`` of
    one capture: realisation 0's is the task's own seed (:func:`task_seed`),
    the others add the realisation's index to its identity, so adding
    realisations never changes the earlier ones.  The CFA is not part of
    it: realisation k of every CFA uses the same seed (paired comparisons,
    study/intervals.py)."""
    return [task_seed(study_seed, scene, luminance) if k == 0 else task_seed(study_seed, scene, luminance, k)
            for k in range(int(offset), int(offset) + int(n))]
