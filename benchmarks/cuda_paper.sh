#!/usr/bin/env bash
# The paper study on a machine with an NVIDIA GPU: Mitsuba's cuda_ad_spectral
# variant renders (chosen automatically when CUDA is present), the evaluation
# runs on WORKERS processes.  Writes timing.json and metrics.csv into OUTDIR,
# which docs/data/cuda-paper/ holds for the run docs/study.md quotes, and
# `python benchmarks/cuda_agreement.py --gpu OUTDIR` compares its values with
# the committed CPU run.
#
#   bash benchmarks/cuda_paper.sh [OUTDIR] [WORKERS]
#
# Needs the package installed (pip install -e .) with OpenEXR >= 3.4: 3.3.x
# cannot read an EXR in a process where Mitsuba has rendered, so every worker
# that rendered a scene rendered it again on reading (as in the run committed
# in docs/data/cuda-paper/, made with 3.3.5).  The committed run carried its
# Python packages as a tarball of the wheels' contents on PYTHONPATH (the
# machine has no network); set SITE_TARBALL to such a .tar.xz to do the same.
set -euo pipefail
out=${1:-results/cuda-paper}
workers=${2:-16}
if [ -n "${SITE_TARBALL:-}" ]; then
  mkdir -p /tmp/site && tar -xJf "$SITE_TARBALL" -C /tmp/site
  export PYTHONPATH=/tmp/site:$PWD
fi
export CFA_MITSUBA_CACHE=${CFA_MITSUBA_CACHE:-/tmp/cfa-mitsuba-cuda-cache}   # cold: every scene rendered
nvidia-smi -L
python3 -c "import mitsuba as mi, drjit as dr; mi.set_variant('cuda_ad_spectral'); print('CUDA backend:', dr.has_backend(dr.JitBackend.CUDA))"
python3 -m cfa_mitsuba study configs/paper.toml --out "$out" --workers "$workers" --quiet
python3 benchmarks/cuda_agreement.py --gpu "$out"
