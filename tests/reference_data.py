"""The metric reference vectors kept in the repository (tests/data/reference/).

Inputs and the values the metrics' original implementations give on them
(the authors' MATLAB code run in GNU Octave, ISETCam, sfrmat3/5, Sharma's
CIEDE2000 table), with each value's oracle, commit and parameters in
``expected.json`` and every file's SHA-256 in ``SHA256SUMS``;
``tests/data/reference/README.md`` says where each came from.  The seven
XYZ arrays are kept verbatim, as the ``.npy`` files the generator wrote,
inside one deflated zip (``inputs/xyz.zip``: 4.1 MB of float32 in 2.0 MB),
so their SHA-256 in ``expected.json`` still names their bytes.
"""

from __future__ import annotations

import io
import json
import zipfile
from functools import lru_cache
from pathlib import Path

import numpy as np
from PIL import Image

__all__ = ["REFERENCE", "EXPECTED", "input_bytes", "load_input", "input_path", "COLOUR_PAIRS", "XYZ_PAIRS",
           "EDGES", "WHITE", "entries", "colour_pair", "xyz_pair", "edge_image"]

REFERENCE = Path(__file__).resolve().parent / "data" / "reference"
EXPECTED = json.loads((REFERENCE / "expected.json").read_text())
_ZIPPED = {"xyz": REFERENCE / "inputs" / "xyz.zip"}


def input_bytes(rel: str) -> bytes:
    """The stored bytes of input ``rel`` (a key of ``EXPECTED['inputs']``, e.g. 'colour/flat_ref.png')."""
    folder, name = rel.split("/", 1)
    if folder in _ZIPPED:
        with zipfile.ZipFile(_ZIPPED[folder]) as archive:
            return archive.read(name)
    return (REFERENCE / "inputs" / rel).read_bytes()


def load_input(rel: str) -> np.ndarray:
    """Input ``rel`` as a float64 array: a PNG's code values as stored, an ``.npy`` array as saved."""
    data = input_bytes(rel)
    if rel.endswith(".npy"):
        return np.load(io.BytesIO(data)).astype(np.float64)
    return np.array(Image.open(io.BytesIO(data))).astype(np.float64)


def input_path(rel: str, folder: Path) -> Path:
    """A file path holding input ``rel`` (for the command line): the stored file, or a copy in ``folder``."""
    top = rel.split("/", 1)[0]
    if top not in _ZIPPED:
        return REFERENCE / "inputs" / rel
    path = Path(folder) / Path(rel).name
    path.write_bytes(input_bytes(rel))
    return path


# -- the pairs and edges the metrics' test files read -------------------------------------------

COLOUR_PAIRS = sorted(EXPECTED["colour_pairs"])
XYZ_PAIRS = sorted(EXPECTED["xyz_pairs"])
EDGES = sorted(EXPECTED["slanted_edges"])
WHITE = [95.05, 100.0, 108.9]


def entries(section, pair, metric, *, oracle=None, primary=None):
    out = [e for e in EXPECTED[section][pair][metric]
           if (oracle is None or e["oracle"] == oracle) and (primary is None or e["primary"] == primary)]
    assert out, (section, pair, metric, oracle)
    return out


@lru_cache(maxsize=None)
def colour_pair(pid):
    p = EXPECTED["colour_pairs"][pid]
    return load_input(p["reference"]), load_input(p["distorted"])


@lru_cache(maxsize=None)
def xyz_pair(pid):
    p = EXPECTED["xyz_pairs"][pid]
    return load_input(p["reference"]), load_input(p["distorted"])


@lru_cache(maxsize=None)
def edge_image(eid):
    p = EXPECTED["slanted_edges"][eid]
    return load_input(p.get("file_npy") or p["file"])
