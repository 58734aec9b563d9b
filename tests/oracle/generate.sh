#!/usr/bin/env bash
# Regenerates the Pinocchio reference values in tests/fixtures/oracle/ that
# tests/oracle_agreement.rs compares quadsim with.
#
#   pip install -r ../shared/oracle/requirements.txt     # pin==4.1.0 (Pinocchio 4.1.0)
#   bash tests/oracle/generate.sh                          # from the repository root
#
# The oracle is ../shared/oracle/oracle.py (override with ORACLE=path/to/oracle.py).
# Each fixture is made by exactly:
#   python3 $ORACLE tests/fixtures/models/quad16.urdf tests/fixtures/oracle/quad16_states.json > quad16_shared.json
#   python3 $ORACLE tests/fixtures/models/<robot>.urdf --random 20 --seed 1   > <robot>_random.json
#   python3 $ORACLE tests/fixtures/models/<robot>.urdf --random 20 --seed 1 --fixed-base > <robot>_fixed.json
# for <robot> in quad16 quad12, and
#   python3 $ORACLE tests/fixtures/models/vendor_style_revolute.urdf --random 20 --seed 1 > vendor_style_random.json
# (offset and rotated inertial frames, a rotated fixed child, a prismatic joint).
# The quad URDFs and quad16_states.json are copies of
# ../shared/models/*.urdf and ../shared/oracle/quad16_states.json (checked below
# when ../shared is there), so the tests never need ../shared.
set -euo pipefail

cd "$(dirname "$0")/../.."
ORACLE="${ORACLE:-../shared/oracle/oracle.py}"
STATES=tests/fixtures/oracle/quad16_states.json
PIN_VERSION="4.1.0"
OUT=tests/fixtures/oracle
MODELS=tests/fixtures/models

got=$(python3 -c 'import pinocchio; print(pinocchio.__version__)')
if [ "$got" != "$PIN_VERSION" ]; then
    echo "generate.sh: Pinocchio $got found, $PIN_VERSION required (pip install pin==$PIN_VERSION)" >&2
    exit 1
fi
for robot in quad16 quad12; do
    if [ -f "../shared/models/$robot.urdf" ] && ! cmp -s "../shared/models/$robot.urdf" "$MODELS/$robot.urdf"; then
        echo "generate.sh: $MODELS/$robot.urdf differs from ../shared/models/$robot.urdf; copy it first" >&2
        exit 1
    fi
done
if [ -f ../shared/oracle/quad16_states.json ] && ! cmp -s ../shared/oracle/quad16_states.json "$STATES"; then
    echo "generate.sh: $STATES differs from ../shared/oracle/quad16_states.json; copy it first" >&2
    exit 1
fi

mkdir -p "$OUT"
python3 "$ORACLE" "$MODELS/quad16.urdf" "$STATES" > "$OUT/quad16_shared.json"
for robot in quad16 quad12; do
    python3 "$ORACLE" "$MODELS/$robot.urdf" --random 20 --seed 1 > "$OUT/${robot}_random.json"
    python3 "$ORACLE" "$MODELS/$robot.urdf" --random 20 --seed 1 --fixed-base > "$OUT/${robot}_fixed.json"
done
python3 "$ORACLE" "$MODELS/vendor_style_revolute.urdf" --random 20 --seed 1 > "$OUT/vendor_style_random.json"
ls -l "$OUT"
