"""The reference vectors in tests/data/reference/ are the stored ones: every file
matches SHA256SUMS, and every input (the XYZ arrays inside their zip included)
has the digest its generator recorded in expected.json."""

from __future__ import annotations

import hashlib

from reference_data import EXPECTED, REFERENCE, input_bytes


def test_every_stored_file_matches_sha256sums():
    listed = {}
    for line in (REFERENCE / "SHA256SUMS").read_text().splitlines():
        digest, rel = line.split("  ", 1)
        listed[rel] = digest
    stored = {str(p.relative_to(REFERENCE)) for p in REFERENCE.rglob("*") if p.is_file()}
    assert stored - {"SHA256SUMS", "README.md"} == set(listed)
    for rel, digest in listed.items():
        assert hashlib.sha256((REFERENCE / rel).read_bytes()).hexdigest() == digest, rel


def test_inputs_are_the_generated_ones():
    assert len(EXPECTED["inputs"]) == 24
    for rel, info in EXPECTED["inputs"].items():
        data = input_bytes(rel)
        assert len(data) == info["bytes"] and hashlib.sha256(data).hexdigest() == info["sha256"], rel
