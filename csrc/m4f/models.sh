#!/bin/sh
# models.sh OUT_DIR - the models the default fit (`pihyst fit`, no options but the
# record's columns, as docs/records.md gives them) produces for the two measured records,
# exported as C headers for bench-m4f (bench.c):
#   kp_p885.h        P-885.91 stack, single precision, without its creep lags
#   kp_p885_creep.h  the same model with its creep lags, single precision (bench.c
#                    takes its _f32 lags, kp_p885_creep_creep_init)
#   kp_smart.h       SmartHysteresis 150 V 1 Hz sine, single precision
# plus models.txt (family, operators, creep lags of each). Run on every bench-m4f, so the
# bench measures whatever the current default fit gives. PIHYST: the pihyst command
# (default: the repository's .venv); the data: pihyst's data root ($PIHYST_DATA or
# ../shared/data beside the repository).
set -eu
out=${1:?usage: models.sh OUT_DIR}
here=$(cd "$(dirname "$0")" && pwd)
PIHYST=${PIHYST:-$here/../../.venv/bin/pihyst}
PYTHON=${PYTHON:-$(dirname "$PIHYST")/python}
data=$("$PYTHON" -c "from pihyst.io import datasets; r = datasets.data_root(); print(r or '')")
if [ -z "$data" ]; then
    echo "models.sh: the measured data sets were not found (set PIHYST_DATA)" >&2
    exit 1
fi
mkdir -p "$out"
"$PIHYST" fit "$data/dbo-pi-p885-micromanipulator/Model_Vi_Do.dat" \
    --voltage 1 --displacement 5 --lag 1 --rate 200 -o "$out/p885.json" > "$out/p885.fit.txt"
"$PIHYST" fit "$data/smarthysteresis-piezo-sine150V1Hz/hysteresis_v_150_1hz.csv" \
    --time 2 --displacement 3 --voltage 4 --skip-until 4.26 -o "$out/smart.json" \
    > "$out/smart.fit.txt"
# the P-885 model without its creep lags, for the single-precision header
"$PYTHON" - "$out" <<'PY'
import json, sys
out = sys.argv[1]
for name in ("p885", "smart"):
    with open(f"{out}/{name}.json") as f:
        model = json.load(f)
    creep = model.pop("creep", None)
    with open(f"{out}/{name}_hysteresis.json", "w") as f:
        json.dump(model, f)
    with open(f"{out}/{name}.models.txt", "w") as f:
        n_ops = len(model["weights"])
        lags = len(creep["tau_s"]) if creep else 0
        f.write(f"{name} {model['family']} {n_ops} operators {lags} creep lags\n")
PY
"$PIHYST" export "$out/p885_hysteresis.json" --c --float -o "$out/kp_p885.h" --name kp_p885
"$PIHYST" export "$out/smart_hysteresis.json" --c --float -o "$out/kp_smart.h" --name kp_smart
if grep -q '"creep"' "$out/p885.json"; then
    "$PIHYST" export "$out/p885.json" --c --float -o "$out/kp_p885_creep.h" --name kp_p885_creep
    echo "#define KP_P885_HAS_CREEP 1" > "$out/kp_p885_creep_flag.h"
else
    echo "#define KP_P885_HAS_CREEP 0" > "$out/kp_p885_creep_flag.h"
fi
cat "$out/p885.models.txt" "$out/smart.models.txt" > "$out/models.txt"
