#!/usr/bin/env bash
# The built-in demo. It grows with the pipeline; for now it describes the
# public test stacks.
set -euo pipefail
cd "$(dirname "$0")/.."
./build/col0rme info ../shared/data/musij/CardioMyoblast_Mitochondria_100Frames_NA1.4_80nm_1x_510nmemission.tif
