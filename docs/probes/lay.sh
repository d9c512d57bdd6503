#!/bin/bash
# lay.sh: from-flat drapes of the corr_c41 presets, laying L, grid G, seed S
D=/work/main/build/bin/drape; P=/work/exp/s9/fits/corr_c41
jobs=()
for L in ${LAYINGS:-0.2 0.3 0.4 0.5 1}; do for g in 41 61 81; do for r in $P/DL-A*.json; do
  case $r in *.fit.json|*.flat*) continue;; esac
  id=$(basename $r .json); echo "$id $g $L"
done; done; done | xargs -P2 -n3 bash -c 'OMP_NUM_THREADS=1 '$D' simulate --fabric '$P'/$0.json --sample-diameter 300mm --disc-diameter 150mm --grid $1 --laying $2 --json --quiet --max-iterations 3000 > lay/$0.g$1.L$2.json 2>/dev/null'
