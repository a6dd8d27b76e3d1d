"""``cfa-mitsuba evaluate``: spectral EXRs a user rendered (or measured)
through CFAs and demosaics with the default optics, sensor and processing,
without a study config: the same tasks as a study's (:mod:`.tasks`), the
same mean table (``metrics.csv``) and failures list."""

from __future__ import annotations

__all__ = ["evaluate_renders"]

import sys
from pathlib import Path

from ..errors import CfaMitsubaError
from ..io import atomic_output, check_writable_dir
from .cfa_facts import write_cfa_facts
from .runner import SCORED_METRICS, _cfa_label, _require_a_measurement, _run_tasks, _write_failures
from .tables import mean_table, order_rows
from .tasks import EvaluationTask, evaluate_task


def evaluate_renders(renders_dir, cfas, demosaics, out_dir, *, luminances=(None,), seed: int = 0,
                     workers: int | None = None, progress: bool = True, log=None, realisations: int = 3):
    """``cfa-mitsuba evaluate``: every spectral EXR in ``renders_dir`` (as
    written by ``cfa-mitsuba render``) through the given CFAs and demosaics,
    with the default optics, sensor and processing.  Each EXR feeds the
    metrics its sidecar declares (a bare JCGT EXR: the image metrics).
    ``luminances`` None keeps each render's own luminance; ``realisations``
    noise realisations per capture (the mean and its 95 % interval, as in a
    study).  Writes ``metrics.csv``; returns the table.
    """
    from .. import io
    from .chain import ChainSettings
    from ..metrics import metrics_for_scene
    from .config import IMAGE_METRICS
    from .executors import make_executor

    log = log or (lambda msg: print(msg, file=sys.stderr))
    rdir = Path(renders_dir)
    if not rdir.is_dir():
        raise CfaMitsubaError(f"--renders: no such directory {str(rdir)!r}")
    exrs = sorted(rdir.glob("*.exr"))
    if not exrs:
        raise CfaMitsubaError(f"--renders: no .exr files in {str(rdir)!r}")
    out = check_writable_dir(out_dir)
    chain = ChainSettings()
    tasks = []
    for exr in exrs:
        img = io.read_spectral_exr(exr)
        meta = img.meta
        scene = str(meta.get("scene") or exr.stem)
        # the metrics its kind feeds (an EXR written before sidecars named the kind lists them)
        metrics = list(metrics_for_scene(meta["kind"]) if meta.get("kind") else meta.get("metrics") or IMAGE_METRICS)
        for lum in luminances:
            level = float(lum) if lum is not None else float(meta.get("luminance_cd_m2") or 100.0)
            for cfa in cfas:
                tasks.append(EvaluationTask(
                    source={"kind": "exr", "path": str(exr.resolve())}, scene=scene,
                    condition=chain.base_condition(luminance=level, seed=seed), cfa=cfa, cfa_label=_cfa_label(cfa),
                    demosaics=tuple(demosaics), metrics=tuple(metrics), chain=chain, realisations=realisations))
    rows, failures = [], []

    def got(task, result):
        rows.extend(result.rows)
        failures.extend(result.failures)

    with make_executor(workers=workers) as executor:
        log(f"evaluate: {len(exrs)} render(s) x {len(cfas)} CFA(s) x {len(demosaics)} demosaic(s) "
            f"on {executor.description}")
        _run_tasks(executor, evaluate_task, tasks, "evaluate", progress, got)
    order = {"scene": [], "cfa": [_cfa_label(c) for c in cfas], "demosaic": list(demosaics),
             "metric": list(SCORED_METRICS)}
    realisations = order_rows(rows, order)
    metrics = mean_table(realisations)
    write_cfa_facts(out, cfas, order["cfa"], chain, chain.base_condition())
    with atomic_output(out / "metrics.csv") as tmp:
        metrics.to_csv(tmp, index=False, float_format="%.10g")
    # a metric that cannot be measured fails in every realisation: list it once, with the first one's reason
    once: dict = {}
    for f in failures:
        once.setdefault(tuple(sorted((k, str(v)) for k, v in f.items() if k not in ("realisation", "error"))), f)
    _write_failures(out, list(once.values()), log)
    _require_a_measurement(rows, failures, out)
    return metrics
