"""``cfa-mitsuba list scenes|cfas|demosaics|metrics``."""

from __future__ import annotations

HELP = "list the built-in scenes, CFAs, demosaicing methods or metrics"

KINDS = ("scenes", "cfas", "demosaics", "metrics")


def add_arguments(parser) -> None:
    parser.add_argument("kind", choices=KINDS, help="what to list")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON array (for metrics: each record's name, scenes, inputs, unit, "
                             "higher_is_better, scored, score_range, label, description)")


def _rows(kind: str) -> list[tuple[str, str]]:
    """(name, one-line description) pairs from the stage registries."""
    if kind == "scenes":
        from ..render import list_scenes

        return list_scenes()
    if kind == "cfas":
        from ..sensor import get_cfa, list_cfas

        rows = []
        for name in list_cfas():
            cfa = get_cfa(name)
            rows.append((name, f"{cfa.tile_text():<40} {cfa.description}"))
        return rows
    if kind == "demosaics":
        from ..isp import list_demosaics

        return list_demosaics()
    from ..metrics import list_metrics

    return list_metrics()


def run(args) -> int:
    if getattr(args, "json", False):
        import json

        if args.kind == "metrics":
            from ..metrics import METRICS, record_json

            payload = [record_json(r) for r in METRICS.values()]
        else:
            payload = [{"name": n, "description": d} for n, d in _rows(args.kind)]
        print(json.dumps(payload, ensure_ascii=False))
        return 0
    rows = _rows(args.kind)
    width = max((len(n) for n, _ in rows), default=0)
    for name, text in rows:
        print(f"{name:<{width}}  {text}".rstrip())
    return 0
