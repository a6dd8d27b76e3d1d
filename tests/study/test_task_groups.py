"""Evaluation tasks go to workers in groups of one render and condition
(issue 25): every task once, a group's tasks share their source and
condition, the largest group first, and groups split when workers would idle."""

from pathlib import Path

from cfa_mitsuba.study.config import load_config
from cfa_mitsuba.study.runner import _render_label, _task_groups, _task_id, plan_study

REPO = Path(__file__).resolve().parents[2]


def _plan():
    config = load_config(REPO / "configs" / "quick.toml")
    _, tasks = plan_study(config, None)
    return config, tasks


def test_groups_cover_every_task_once_and_share_render_and_condition():
    config, tasks = _plan()
    sizes = {_render_label(t.source): {"width": 100, "height": 100} for t in tasks}
    sizes[_render_label(next(t.source for t in tasks if t.scene == "macbeth"))] = {"width": 1000, "height": 1000}
    groups = _task_groups(tasks, sizes, workers=1)
    assert sorted(_task_id(t) for g in groups for t in g) == sorted(_task_id(t) for t in tasks)
    for g in groups:
        assert len({(repr(t.source), repr(t.condition), t.render_seed) for t in g}) == 1
    whole = {}
    for t in tasks:
        whole.setdefault((repr(t.source), repr(t.condition), t.render_seed), []).append(t)
    if len(whole) >= 4:  # no split needed for one worker: each group is a whole render-and-condition
        assert len(groups) == len(whole)
    assert groups[0][0].scene == "macbeth"  # ten times the pixels: first


def test_groups_split_so_every_worker_has_work():
    _, tasks = _plan()
    groups = _task_groups(tasks, {}, workers=len(tasks))
    assert len(groups) == len(tasks)  # as many workers as tasks: one task each
    few = _task_groups(tasks, {}, workers=2)
    assert len(few) >= min(8, len(tasks))
