"""Options out of range for every command: NaN, infinities, negative, zero where invalid,
absurdly large, wrong type; outputs that cannot be written.

Each case is ``(argv, expected status, fragment of the error)``; ``{model}``, ``{volts}``,
``{desired}``, ``{loop}`` and ``{out}`` stand for corpus inputs and the output path.
"""

PREDICT = ["predict", "{model}", "{volts}", "-o", "{out}"]
FIT = ["fit", "{loop}", "-o", "{out}"]
COMPENSATE = ["compensate", "{model}", "{desired}", "-o", "{out}"]
TRACK = ["track", "{model}", "{desired}", "-o", "{out}"]
SIMULATE = ["simulate", "-o", "{out}", "--period", "20", "--dt", "1"]
REPORT = ["report", "{loop}", "--out", "{out}"]
DEMO = ["demo", "--out", "{out}"]
LEARN = ["learn", "--scan", "100", "--trials", "1", "-o", "{out}"]

NUMBERS_BAD = ("nan", "inf", "-inf", "abc", "", "1e400")

CASES = []


def case(argv, expect, says=None):
    CASES.append((argv, expect, says))


# outputs that cannot be written: named by the path the user gave
for base in (PREDICT, FIT, COMPENSATE, TRACK, SIMULATE):
    o = base.index("{out}")
    case(base[:o] + ["{tmp}/missing-folder/out.csv"] + base[o + 1:], 2,
         "missing-folder/out.csv")
    case(base[:o] + ["{tmp}"] + base[o + 1:], 2, "is a folder")
    case(base[:o] + ["{tmp}/file.txt/out.csv"] + base[o + 1:], 2, "file.txt/out.csv")
for base in (PREDICT, COMPENSATE, TRACK):
    case(base[:1] + ["{tmp}/no-such-model.json"] + base[2:], 2, "no-such-model.json")
    case(base[:1] + ["{tmp}"] + base[2:], 2, "")
    case(base[:2] + ["{tmp}/no-such.csv"] + base[3:], 2, "no-such.csv")
    case(base[:2] + ["{tmp}"] + base[3:], 2, "")
case(["fit", "{tmp}/no-such.csv", "-o", "{out}"], 2, "no-such.csv")
case(["fit", "{tmp}", "-o", "{out}"], 2, "")

# fit
for v in NUMBERS_BAD + ("-1", "0,0", "5,1", "0,,10", ",", "1e400,2", "0;10"):
    case(FIT + ["--thresholds", v], 2, "--thresholds")
case(FIT + ["--thresholds", "0,10,30"], 0)
case(FIT + ["--thresholds", "0,10,1000"], 2, "threshold")
for v in ("0", "-1", "x", "1.5", "1000000000", "99999999999999999999999"):
    case(FIT + ["--n-operators", v], 2, "--n-operators")
for v in ("0", "1", "-5", "x", "1000000000", "99999999999999999999999"):
    case(FIT + ["--candidates", v], 2, "--candidates")
case(FIT + ["--candidates", "8"], 0)
for v in ("1", "-0.5", "2", "nan", "inf", "abc", "", "1e-400"):
    case(FIT + ["--holdout", v], 2, "--holdout")
for v in ("0.5", "none", "alternate"):
    case(FIT + ["--holdout", v], 0)
case(FIT + ["--model", "quadratic"], 2, "--model")
case(FIT + ["--model", ""], 2, "--model")
case(FIT + ["--initial-state", "hot"], 2, "--initial-state")
case(FIT + ["--unknown-option"], 2, "--unknown-option")
case(["fit", "{loop}"], 2, "-o")

for v in NUMBERS_BAD + ("0", "-1"):
    case(FIT + ["--max-latency", v], 2, "--max-latency")
for v in ("0", "-1", "x", "1.5"):
    case(FIT + ["--max-operators", v], 2, "--max-operators")

# fit-many takes fit's size options with fit's limits, refused before any record is read
FIT_MANY = ["fit-many", "{tmp}", "-o", "{tmp}/models"]
for v in ("129", "1000000", "1", "0", "x", "99999999999999999999999"):
    case(FIT_MANY + ["--candidates", v], 2, "argument --candidates: must be")
for v in ("129", "200", "0", "x"):
    case(FIT_MANY + ["--n-operators", v], 2, "argument --n-operators: must be")
case(FIT_MANY + ["--thresholds", ",".join(str(i) for i in range(129))], 2,
     "--thresholds: 129 thresholds, at most 128")

# an empty output name names its option (never a folder, never a temporary)
for base in (PREDICT, FIT, COMPENSATE, TRACK, SIMULATE):
    o = base.index("{out}")
    case(base[:o] + [""] + base[o + 1:], 2, "argument -o: an empty file name")
case(REPORT[:3] + [""], 2, "argument --out: an empty file name")

# compensate and track: voltage limits and slew rate
for base in (COMPENSATE, TRACK):
    for opt in ("--u-min", "--u-max"):
        for v in NUMBERS_BAD + ("-1e300", "1e300"):
            case(base + [opt, v], 2, opt)
    case(base + ["--u-min", "100", "--u-max", "50"], 2, "--u-min 100 must be below")
    case(base + ["--u-min", "50", "--u-max", "50"], 2, "--u-min 50 must be below")
    for v in NUMBERS_BAD + ("0", "-1", "-0"):
        case(base + ["--slew-rate", v], 2, "--slew-rate")
    case(base + ["--slew-rate", "1e-300"], 0)
    case(base + ["--slew-rate", "1e300"], 0)
    case(base + ["--u-min", "10", "--u-max", "40"], 0)
case(COMPENSATE[:2] + ["{volts}"] + COMPENSATE[3:] + ["--slew-rate", "5"], 0)

# beam options (simulate, track)
for base in (SIMULATE, TRACK):
    for v in ("-1", "-99999999999999999999999", "1.5", "x", "nan"):
        case(base + ["--seed", v], 2, "--seed")
    case(base + ["--seed", "99999999999999999999999"], 0)
    case(base + ["--plant", "granite"], 2, "--plant")

# simulate
for opt in ("--dt", "--period"):
    for v in NUMBERS_BAD + ("0", "-1", "-0"):
        case(SIMULATE + [opt, v], 2, opt)
case(SIMULATE + ["--dt", "1e-300"], 2, "samples")
case(SIMULATE + ["--period", "1e300"], 2, "samples")
case(SIMULATE + ["--dt", "1e300"], 2, "--dt")
for v in ("0", "-1", "x", "1.5", "100000000", "99999999999999999999999"):
    case(SIMULATE + ["--cycles", v], 2, "--cycles")
for v in NUMBERS_BAD + ("-1", "200", "-1e300"):
    case(SIMULATE + ["--min", v], 2, "--min")
    case(SIMULATE + ["--max", v], 2, "--max")
case(SIMULATE + ["--min", "100", "--max", "50"], 2, "--min")
case(SIMULATE + ["--min", "50", "--max", "50"], 2, "--min")
case(SIMULATE + ["--signal", "square"], 2, "--signal")
DT = SIMULATE
for v in ("0", "-1", "x", "1000000000", "99999999999999999999999"):
    case(DT + ["--signal", "decaying-triangles", "--triangles", v], 2, "--triangles")
    case(DT + ["--signal", "random-ramps", "--ramps", v], 2, "--ramps")
    case(DT + ["--signal", "staircase", "--steps", v], 2, "--steps")
for v in NUMBERS_BAD + ("0", "1", "-0.5", "2"):
    case(DT + ["--signal", "decaying-triangles", "--ratio", v], 2, "--ratio")
for v in NUMBERS_BAD + ("0", "-1", "1e-300"):
    case(DT + ["--signal", "random-ramps", "--rate", v], 2, "--rate")
for v in NUMBERS_BAD + ("0", "-1", "1e300"):
    case(DT + ["--signal", "staircase", "--step-time", v], 2, "--step-time")
for signal in ("triangle", "sine", "decaying-triangles", "random-ramps", "staircase"):
    case(DT + ["--signal", signal], 0)
case(SIMULATE + ["--cycles", "3", "--no-noise", "--no-creep", "--no-quantisation",
                 "--dynamics"], 0)

# report and demo: the options are checked before any work
case(REPORT[:3] + ["{tmp}/file.txt"], 2, "file.txt")
case(["report", "{tmp}/no-such.csv"], 2, "no-such.csv")
case(["report", "{tmp}/bad.csv", "--out", "{out}"], 2, "bad.csv")
case(DEMO[:2] + ["{tmp}/file.txt"], 2, "file.txt")
case(DEMO + ["--seed", "-1"], 2, "--seed")
case(DEMO + ["--seed", "x"], 2, "--seed")
case(DEMO + ["--plant", "granite"], 2, "--plant")

# learn (a simulated stage): every number checked before any trial
o = LEARN.index("{out}")
case(LEARN[:o] + ["{tmp}/missing-folder/out.csv"], 2, "missing-folder/out.csv")
case(LEARN[:o] + ["{tmp}"], 2, "is a folder")
for option in ("--clock", "--slew", "--bandwidth"):
    for v in NUMBERS_BAD + ("0", "-1"):
        case(LEARN + [option, v], 2, option)
for v in NUMBERS_BAD + ("-1",):
    case(LEARN + ["--noise", v], 2, "--noise")
for v in ("nan", "inf", "-inf", "200", "-1"):
    case(LEARN + ["--u-min", v], 2, "--u-min")
for v in ("nan", "0", "1e400", "1e-300", "500"):
    case(["learn", "--scan", v, "-o", "{out}"], 2, "--scan")
for v in ("0", "x", "1e9", "nan", "0,0.04", "800,0", "800,1", "800,nan", "800,0.04,1"):
    case(LEARN + ["--mode", v], 2, "--mode")
for v in ("-1", "x", "101"):
    case(LEARN + ["--delay", v], 2, "--delay")
case(LEARN + ["--clock", "1e9"], 2, "--scan 100 at --clock 1e+09")
case(LEARN + ["--model", "{tmp}/no-such-model.json"], 2, "no-such-model.json")
case(["learn", "--desired", "{tmp}/no-such.csv", "-o", "{out}"], 2, "no-such.csv")
case(["learn", "-o", "{out}"], 2, "--scan")
case(LEARN, 0)

# the command line itself
case([], 2, "COMMAND")
case(["frobnicate"], 2, "frobnicate")
case(["predict"], 2, "")
