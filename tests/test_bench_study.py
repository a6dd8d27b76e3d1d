"""benchmarks/bench_study.py's derived figures: each scene's floor (its
worker seconds over the cores) and the evaluate time a target ratio needs."""

import importlib.util
from pathlib import Path

import pytest

_SPEC = importlib.util.spec_from_file_location(
    "bench_study", Path(__file__).resolve().parents[1] / "benchmarks" / "bench_study.py")
bench_study = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(bench_study)


def _run(evaluate_s, scenes):
    return {"evaluate_s": evaluate_s, "scenes": scenes}


def test_a_scene_floor_is_its_worker_seconds_of_every_stage_over_the_cores():
    got = _run(100.0, {"puppy": {"tasks": 3, "captures": 9, "outputs": 36, "optics_s": 1.0, "capture_s": 3.0,
                                 "process_s": 10.0, "metrics_s": 26.0},
                       "chirp": {"captures": 9, "metrics_s": 0.5}})
    assert bench_study.scene_floors(got, 2) == {"puppy": pytest.approx(20.0), "chirp": pytest.approx(0.25)}
    assert bench_study.scene_floors({"evaluate_s": 1.0}, 2) == {}  # a tree whose timing has no scenes


def test_the_target_is_the_other_trees_evaluate_time_over_the_ratio():
    record = {"against": "abc123", "runs": {"this": {"warm": _run(232.0, {})},
                                            "abc123": {"warm": _run(264.6, {})}}}
    bench_study.add_target(record, 1.8)
    assert record["target"] == {"ratio": 1.8, "mode": "warm", "evaluate_s": pytest.approx(147.0)}
