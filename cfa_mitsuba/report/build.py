"""Build the report of a results directory: figures, tables, report.html."""

from __future__ import annotations

__all__ = ["build_report", "report_workers", "FIGURE_FORMATS"]

import time
import warnings
from pathlib import Path

from ..errors import CfaMitsubaError
from ..io.owned import prune_written, record_written
from .figure import RC, Absent, ReportFigure, figure_bytes
from .results import Results, load_results

#: Figure file formats the report can write (matplotlib's writers).
FIGURE_FORMATS = ("png", "svg", "pdf")
_MIME = {"png": "image/png", "svg": "image/svg+xml", "jpeg": "image/jpeg"}
#: An image sheet whose PNG is larger than this is embedded as JPEG (quality
#: 90, no chroma subsampling); the PNG in figures/ stays lossless.
_MAX_EMBED_PNG = 900_000


def _figure_functions(res: Results, thumbnails: bool):
    from . import figures_detail as fd
    from . import figures_sensor as fsen
    from . import figures_sweep as fsw
    from . import figures_scores as fs
    from . import low_light, tiles

    from . import figures_ranks as fr

    if len(res.cfas) > fr.HEATMAP_ABOVE:  # a radar of more polygons cannot be read
        yield fr.score_heatmap
    else:
        yield fs.radar_per_demosaic
        yield fs.radar_per_cfa
    yield fr.rank_chart
    yield tiles.tiles_by_family
    from .noise_steps import noise_figures
    from .patch_errors import patch_error_sheet

    yield patch_error_sheet
    yield fd.patch_ab
    yield fd.patch_xy
    yield fd.scielab_maps
    yield fd.mtf_curves
    yield fd.moire_curves
    yield fd.gray_bar_profiles
    yield noise_figures
    yield fs.luminance_sweep
    yield low_light.snr_figure
    from .processing import acutance_ysnr_figure

    yield acutance_ysnr_figure
    yield fsen.sensor_curves
    for axis in res.swept_axes:
        def by_axis(r, axis=axis):
            return fsw.axis_sweep(r, axis)
        by_axis.__name__ = f"axis_sweep[{axis}]"
        yield by_axis
    from .crops import crop_sheets

    yield crop_sheets
    if thumbnails and res.primary_luminance is not None:
        for scene in res.scenes:
            def sheet(r, scene=scene):
                return fd.thumbnail_sheet(r, scene, r.primary_luminance)
            sheet.__name__ = f"thumbnail_sheet[{scene}]"
            yield sheet


def _draw_one(res: Results, fn, formats) -> tuple[list, list, dict, dict, list]:
    """Draw one figure function's figures and encode them: (figures, absents,
    files {key: {fmt: bytes}}, embeds {key: (bytes, mime)}, log lines).  The
    figures come back released (:meth:`ReportFigure.release`): their bytes
    are made, so the matplotlib objects are freed, and a worker process can
    send them back."""
    name = getattr(fn, "__name__", "figure")
    t = time.perf_counter()
    figures, absents, files, embeds = [], [], {}, {}
    try:
        out = fn(res)
    except Exception as exc:  # a bug must not lose a finished study's report
        msg = f"{name} failed: {type(exc).__name__}: {exc}"
        warnings.warn(f"cfa-mitsuba report: {msg}", RuntimeWarning, stacklevel=2)
        absents.append(Absent(_section_of(name), name, f"could not be drawn ({msg}); this is a bug, "
                              "please report it with the results directory"))
        return figures, absents, files, embeds, []
    drawn = time.perf_counter() - t
    for item in out if isinstance(out, list) else [out]:
        if isinstance(item, ReportFigure):
            files[item.key], embeds[item.key] = _encode(item, formats)
            item.release()
            figures.append(item)
        else:
            absents.append(item)
    return figures, absents, files, embeds, [f"  {name}: {drawn:.2f} s, encoded in {time.perf_counter() - t - drawn:.2f} s"]


#: the results a report worker process loaded, with the key they were loaded for
_WORKER_RESULTS: dict = {}


def _worker_draw(job: tuple) -> tuple:
    """:func:`_draw_one` of one figure function in a report worker process.
    ``job``: (index in :func:`_figure_functions`, results directory, timing,
    thumbnails, formats); the results are loaded once per process."""
    import json

    import matplotlib

    index, out_dir, timing, thumbnails, formats = job
    key = (out_dir, json.dumps(timing, sort_keys=True, default=str))
    if _WORKER_RESULTS.get("key") != key:
        _WORKER_RESULTS.update(key=key, res=_load(out_dir, timing))
    res = _WORKER_RESULTS["res"]
    fn = list(_figure_functions(res, thumbnails))[index]
    with matplotlib.rc_context(RC):
        return _draw_one(res, fn, formats)


def _draw(res: Results, thumbnails: bool, formats, workers: int, timing: dict | None, log,
          progress: bool = False) -> tuple:
    """(figures, absents, files, embeds) of every figure function, in their
    order; drawn and encoded in ``workers`` processes when more than one
    (each loads the results once and takes the next figure function as it
    comes free; drawing and encoding are single-threaded matplotlib and
    Pillow work, and they are most of a large report's time)."""
    from ..io.progress import progress_bar

    fns = list(_figure_functions(res, thumbnails))
    parts: dict = {}
    bar = progress_bar(len(fns), "report", enabled=progress, unit="figure")
    try:
        if workers > 1 and len(fns) > 1:
            parts = _draw_in_processes(res, len(fns), thumbnails, formats, min(workers, len(fns)), timing, log, bar)
        for i, fn in enumerate(fns):  # sequentially: everything, or what the processes did not return
            if i not in parts:
                parts[i] = _draw_one(res, fn, formats)
                bar.update(1)
    finally:
        bar.close()
    figures, absents, files, embeds = [], [], {}, {}
    for i in range(len(fns)):
        f, a, fl, e, lines = parts[i]
        figures += f
        absents += a
        files.update(fl)
        embeds.update(e)
        for line in lines:
            log(line)
    if not thumbnails:
        absents.append(Absent("outputs", "Camera outputs", "thumbnails are turned off (output.thumbnails = false)"))
    return figures, absents, files, embeds


def _draw_in_processes(res: Results, n: int, thumbnails: bool, formats, workers: int, timing, log, bar) -> dict:
    """{figure function index: :func:`_draw_one`'s result} from ``workers``
    processes (the study's local executor: spawned, their thread budget
    set, ended with this process); whatever they could not return (a
    process that would not start or died) is left out, and :func:`_draw`
    draws it here."""
    from ..study.executors import LocalExecutor

    parts: dict = {}
    jobs = [(i, str(res.root), timing, thumbnails, formats) for i in range(n)]
    try:
        with LocalExecutor(workers) as pool:
            for job, got in pool.map_unordered(_worker_draw, jobs):
                parts[job[0]] = got
                bar.update(1)
    except Exception as exc:  # noqa: BLE001 - a lost process costs time, never the report
        log(f"  report worker processes failed ({type(exc).__name__}: {exc}); drawing the rest here")
    return parts


def _load(out_dir, timing: dict | None) -> Results:
    """The results of ``out_dir``, with ``timing`` in place of timing.json's when given."""
    res = load_results(out_dir)
    if timing is not None:
        res.timing = dict(timing)
        res.notes = [n for n in res.notes if not n.startswith("timing.json")]
    return res


def report_workers(workers: int | None) -> int:
    """The processes a report is drawn in: ``workers`` (default: a study's,
    :func:`~cfa_mitsuba.study.executors.default_workers`), at most the cores
    this process may use, at least 1."""
    from ..study.executors import _cpu_count, default_workers

    return max(1, min(int(workers or default_workers()), _cpu_count()))


def _check_workers(workers) -> int:
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise CfaMitsubaError(f"report workers must be a whole number >= 1, got {workers!r}")
    return workers


def _section_of(name: str) -> str:
    for key, sec in (("crop", "crops"), ("noise", "noise"), ("radar", "scores"), ("heatmap", "scores"), ("rank", "scores"), ("patch", "colour"), ("scielab", "scielab"),
                     ("mtf", "mtf"), ("moire", "moire"), ("gray", "achromatic"), ("sweep", "sweep"),
                     ("thumb", "outputs"), ("sensor", "sensor")):
        if key in name:
            return sec
    return "scores"


def _encode(fig: ReportFigure, formats) -> tuple[dict, tuple[bytes, str]]:
    """The figure's files {fmt: bytes} and (bytes, mime) embedded in the page.

    A matplotlib figure is written in each format and embedded as SVG when
    one was made (sharp at any zoom), else PNG; an image sheet is PNG only,
    embedded as JPEG when its PNG is large (photographic noise does not
    compress)."""
    if fig.image is not None:
        png = _png_of(fig.image)
        files = {"png": png} if formats else {}
        if len(png) > _MAX_EMBED_PNG and not fig.lossless:
            return files, (_jpeg(fig.image), _MIME["jpeg"])
        return files, (png, _MIME["png"])
    files = {fmt: figure_bytes(fig.figure, fmt) for fmt in formats}
    if not fig.raster and "svg" in files:
        return files, (files["svg"], _MIME["svg"])
    png = files.get("png") or figure_bytes(fig.figure, "png")
    return files, (png, _MIME["png"])


def _png_of(image) -> bytes:
    """An image sheet (camera outputs, S-CIELAB maps) as PNG bytes, at zlib
    level 1: the paper study's six sheets took 6.0 s at level 6 and 2.0 s at
    level 1 for 17 % more bytes (their noise hardly compresses; measured
    with Pillow on this project's machine)."""
    import io

    buf = io.BytesIO()
    image.save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


def _jpeg(image) -> bytes:
    import io

    buf = io.BytesIO()
    image.convert("RGB").save(buf, format="JPEG", quality=90, subsampling=0, optimize=True)
    return buf.getvalue()


def _write(path: Path, data) -> None:
    from ..io import atomic_output

    with atomic_output(path) as tmp:
        if isinstance(data, bytes):
            tmp.write_bytes(data)
        else:
            tmp.write_text(data, encoding="utf-8")


def _moire_sensitivity(res: Results):
    from .moire_sensitivity import sensitivity_table

    return sensitivity_table(res)


def _facts(res: Results) -> dict:
    facts: dict = {}
    s = res.scores
    lum = res.primary_luminance
    if s is not None and lum is not None and len(s):
        # the cards (who is first, by the rank-interval rule) are decision_panel.summary_cards
        if "out_of_range" in s.columns:
            lines = []
            from .style import fmt_value, metric_display

            for m, g in s[s["out_of_range"]].groupby("metric", sort=False):
                worst, best = float(g["worst"].iloc[0]), float(g["best"].iloc[0])
                info = metric_display(m)
                beyond_best = ((g["raw_score"] > 1.0) if "raw_score" in g.columns else g["value"] == g["value"])
                n_b = int(beyond_best.sum())
                n_w = len(g) - n_b
                side = []
                if n_b:
                    side.append(f"{n_b} beyond the best end")
                if n_w:
                    side.append(f"{n_w} beyond the worst end")
                note = ""
                if m == "moire":
                    from .tables import _bound_mark

                    n_lb = sum(1 for r in g.itertuples(index=False) if _bound_mark(res, r)[0])
                    if n_lb:
                        note = (f"; {n_lb} of them found no moiré up to the chirp's top frequency, so their MSP is "
                                "a lower bound in every realisation (≥ in Table 2)")
                lines.append(f"{info.short}: {len(g)} value(s) outside {fmt_value(m, worst)} … "
                             f"{fmt_value(m, best)} {info.unit} ({', '.join(side)}; measured "
                             f"{fmt_value(m, g['value'].min())} … {fmt_value(m, g['value'].max())}{note}).")
            facts["oor_lines"] = lines
    from .figures_sensor import spectra_note

    if spectra_note(res):
        facts["spectra_note"] = spectra_note(res)
    t = res.timing
    if isinstance(t, dict):
        p = t.get("phases") or {}
        if p:
            parts = [f"{k[:-2]} {float(v):.1f} s" for k, v in p.items() if k.endswith("_s") and k != "total_s"]
            total = p.get("total_s")
            # built inside a study the phases have no report_s yet: the total then stops before the report,
            # and timing.json's total (written after it) adds the report's own time
            whole = "in all" if "report_s" in p else "before this report (timing.json's total adds the report's time)"
            text = (f"{float(total):.1f} s {whole}" if total is not None else "") + (
                f" ({', '.join(parts)})" if parts else "")
            renders = t.get("renders") or {}
            if renders:
                reused = sum(1 for r in renders.values() if isinstance(r, dict) and r.get("reused"))
                text += f"; {len(renders) - reused} scene(s) rendered, {reused} reused from the cache"
            if t.get("stale"):
                text += " (from an earlier run: see the note below)"
            facts["timing"] = text.strip()
    return facts


def build_report(out_dir, *, formats=("png", "svg"), thumbnails: bool = True, timing: dict | None = None,
                 log=None, workers: int = 1, progress: bool = False) -> Path:
    """Build ``out_dir/report.html`` and ``out_dir/figures/*`` from a study's
    results directory (see :mod:`cfa_mitsuba.report`).

    Parameters
    ----------
    out_dir : a results directory: ``metrics.csv`` at least; ``scores.csv``,
        ``ranges.json``, ``timing.json``, ``config.json`` and ``details/``
        are used when present, and the report says what is absent.
    formats : figure files to write under ``figures/`` ('png', 'svg',
        'pdf'; empty: none; the page embeds its figures either way).
    thumbnails : draw the sheets of camera outputs (they are the largest
        part of the page).
    timing : the study's timing (as timing.json holds it), for a runner that
        builds the report before it writes timing.json; default: the file.
    log : callable taking one line (default: silent); gets per-figure times.
    workers : processes that draw and encode the figures (default 1: this
        one; more: spawned processes, each loading the results once; the
        files and the page are the same bytes either way).
    progress : a bar on a terminal, one step per figure function.

    Returns
    -------
    Path of ``report.html``.

    Raises
    ------
    CfaMitsubaError
        ``out_dir`` is missing or holds no ``metrics.csv``, or a format is unknown.
    """
    import matplotlib

    log = log or (lambda msg: None)
    if isinstance(formats, str):
        formats = (formats,)
    formats = tuple(dict.fromkeys(str(f).lower().lstrip(".") for f in (formats or ())))
    bad = [f for f in formats if f not in FIGURE_FORMATS]
    if bad:
        raise CfaMitsubaError(f"unknown figure format(s) {', '.join(map(repr, bad))} "
                              f"(known: {', '.join(FIGURE_FORMATS)})")
    workers = _check_workers(workers)
    t0 = time.perf_counter()
    res = _load(out_dir, timing)
    root = res.root
    fig_dir = root / "figures"
    with matplotlib.rc_context(RC):
        t = time.perf_counter()
        figures, absents, files, embeds = _draw(res, thumbnails, formats, workers, timing, log, progress)
        log(f"  figures drawn and encoded in {time.perf_counter() - t:.2f} s ({workers} process(es))")
    from . import page, tables
    from .low_light import low_light_tables
    from .processing import processing_html

    tabs = {
        "table1": tables.table1(res),
        "table2": [(L, tables.table2(res, L)) for L in res.base_luminances if tables.table2(res, L)],
        "table3": [(L, tables.table3(res, L)) for L in res.base_luminances if tables.table3(res, L)],
        "other": tables.other_table(res),
        "sweep": tables.sweep_table(res),
        "ranges": tables.ranges_table(res),
        "policies": tables.policy_table(res),
        "low_light": low_light_tables(res),
        "moire_thresholds": _moire_sensitivity(res),
        "section:processing": processing_html(res),
    }
    text = page.render_page(res, figures=figures, absents=absents, embeds=embeds, tables=tabs, facts=_facts(res))
    # figures/: this build's files only (a rebuild must not leave figures of CFAs no longer in the
    # results); with no formats asked for, figures/ is left as it is
    if formats:
        fig_dir.mkdir(exist_ok=True)
        keep = {f"{k}.{fmt}" for k, by in files.items() for fmt in by}
        prune_written(fig_dir, keep)  # only files an earlier build recorded writing: never the user's
    for key, by in files.items():
        for fmt, data in by.items():
            _write(fig_dir / f"{key}.{fmt}", data)
    if formats:
        record_written(fig_dir, keep)
    path = root / "report.html"
    _write(path, text)
    log(f"report: {len(figures)} figure(s), {len(absents)} absent, {len(text) / 1e6:.1f} MB, "
        f"{time.perf_counter() - t0:.1f} s")
    return path
