"""``cfa-mitsuba list scenes|cfas|spectra|sensors|demosaics|denoise|sharpen|metrics``."""

from __future__ import annotations

HELP = ("list the built-in scenes, CFAs, spectra sets, sensor presets, demosaicing methods, denoisers and "
        "sharpeners (denoise), sharpeners alone (sharpen) or metrics")

KINDS = ("scenes", "cfas", "spectra", "sensors", "demosaics", "denoise", "sharpen", "metrics")


def add_arguments(parser) -> None:
    parser.add_argument("kind", choices=KINDS, help="what to list")
    parser.add_argument("files", nargs="*", metavar="FILE.toml",
                        help="for sensors: sensor files to list after the presets (besides those in the folders "
                             "of $CFA_MITSUBA_SENSORS; docs/sensor.md, 'Bring your own sensor')")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON array (for metrics: each record's name, scenes, inputs, unit, "
                             "higher_is_better, scored, score_range, label, description)")


def _sensor_rows(files) -> list[tuple[str, str]]:
    from ..sensor import get_sensor_preset, list_sensor_presets
    from ..sensor.presets import user_sensor_files

    rows = []
    for n in list(list_sensor_presets()) + user_sensor_files() + list(files):
        p = get_sensor_preset(n)
        q = p.params
        spectra = f"spectra {p.spectra}" if p.spectra else f"own QE curves ({', '.join(p.cfa().channels)})"
        rows.append((p.name, f"{p.description}; {q.pixel_pitch_um:g} um, fill {q.fill_factor:g}, "
                             f"well {q.well_capacity_e:.0f} e-, read noise {q.read_noise_e:.3g} e-, "
                             f"dark {q.dark_current_e_s:.3g} e-/s, PRNU {q.prnu_percent:g} %, "
                             f"{q.adc_bits} bit, black {q.black_level_dn:g} DN; CFA {p.cfa_name}, "
                             f"{spectra}; source: {p.source or 'not given'}" + (f"; file {n}" if p.path else "")))
    return rows


def _rows(kind: str) -> list[tuple[str, str]]:
    """(name, one-line description) pairs from the stage registries."""
    if kind == "scenes":
        from ..render import list_scenes

        return list_scenes()
    if kind == "cfas":
        from ..sensor import get_cfa, list_cfas
        from ..sensor.cfa import layout_info, list_layouts

        rows = []
        for name in list_cfas():
            cfa = get_cfa(name)
            src = layout_info(name)["source"] if name in list_layouts() else "user"
            rows.append((name, f"{cfa.tile_text():<40} {cfa.description}; spectra {cfa.spectra or 'own'}; "
                               f"source: {src}"))
        return rows
    if kind == "spectra":
        from ..sensor import get_spectra_set, list_spectra_sets

        return [(n, f"{', '.join(s.letters)}: {s.description}; source: {s.source}")
                for n, s in ((n, get_spectra_set(n)) for n in list_spectra_sets())]
    if kind == "demosaics":
        from ..isp import list_demosaics
        from ..isp.suitability import SUITS_WITHIN_DB, suitability

        rows = []
        for name, text in list_demosaics():
            suits, avoid = suitability(name)
            if suits or avoid:
                text += (f"; suits (within {SUITS_WITHIN_DB:g} dB of the best measured PSNR): "
                         f"{', '.join(suits) or 'none'}")
                if avoid:
                    text += "; avoid (bilinear beats it): " + ", ".join(f"{lay} by {db:.1f} dB" for lay, db in avoid)
                    text += " (read them with readout remosaic or bin: a Bayer mosaic)"
            rows.append((name, text))
        return rows
    if kind in ("denoise", "sharpen"):
        from ..isp import list_denoisers, list_sharpeners

        # 'denoise' lists both ISP stages, each row naming its stage; 'sharpen' the sharpeners alone
        sharp = [(n, f"sharpen: {d}") for n, d in list_sharpeners()]
        return sharp if kind == "sharpen" else [(n, f"denoise: {d}") for n, d in list_denoisers()] + [
            (n, d) for n, d in sharp if n != "none"]
    from ..metrics import list_metrics

    return list_metrics()


def _rows_for(kind: str, files) -> list[tuple[str, str]]:
    return _sensor_rows(files) if kind == "sensors" else _rows(kind)


def run(args) -> int:
    files = list(getattr(args, "files", []) or [])
    if files and args.kind != "sensors":
        from ..errors import CfaMitsubaError

        raise CfaMitsubaError(f"files are listed only with 'sensors', not with {args.kind!r}")
    if getattr(args, "json", False):
        import json

        if args.kind == "metrics":
            from ..metrics import METRICS, record_json

            payload = [record_json(r) for r in METRICS.values()]
        else:
            payload = [{"name": n, "description": d} for n, d in _rows_for(args.kind, files)]
        print(json.dumps(payload, ensure_ascii=False))
        return 0
    rows = _rows_for(args.kind, files)
    width = max((len(n) for n, _ in rows), default=0)
    for name, text in rows:
        print(f"{name:<{width}}  {text}".rstrip())
    return 0
