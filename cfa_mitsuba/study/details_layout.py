"""The layout of a study's ``details/`` folder, which the study writes
(:mod:`.tasks`) and the report and the design report read:

    details/<scene>/<CFA label>/<demosaic>/<tag>.json   curves and tables
                                           <tag>.png    thumbnail
                                           <tag>.scielab.npy  reduced S-CIELAB map
    details/<scene>/ideal/<tag>.json, .png              the ideal sensor's

``<tag>`` names the condition (``L100``, ``L100_f8``: :meth:`.conditions.Condition.label`);
scene and CFA labels go through :func:`safe_label`.
"""

from __future__ import annotations

__all__ = ["safe_label", "output_folder", "ideal_folder"]

from pathlib import Path


def safe_label(label: str) -> str:
    """The file-name-safe form of a label: the folder a scene or CFA gets
    under ``details/`` (TOML CFAs are labelled by their name, which may hold
    any character)."""
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in str(label))


def output_folder(details_dir, scene: str, cfa_label: str, demosaic: str) -> Path:
    """The folder of one camera output's details (a CFA and a demosaic on a scene)."""
    return Path(details_dir) / safe_label(scene) / safe_label(cfa_label) / str(demosaic)


def ideal_folder(details_dir, scene: str) -> Path:
    """The folder of the ideal sensor's details on a scene."""
    return Path(details_dir) / safe_label(scene) / "ideal"
