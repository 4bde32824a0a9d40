"""Never destroy an input (issue 24, item 1): an output path that is one of the
command's inputs (the same file, also through a symbolic or a hard link) is refused with
exit status 2 before anything is read, and the input is left as it was; an empty output
name is an error naming the option."""

import os
import shutil

import pytest
from harness import DESIRED, GOOD_MODEL, LOOP, REPO, VOLTS, run

RIG = os.path.join(REPO, "examples", "rig", "emulated.toml")

# (command with {inputs}, the input that -o names)
CASES = {
    "predict-input": (["predict", "{model}", "{volts}"], "volts"),
    "predict-model": (["predict", "{model}", "{volts}"], "model"),
    "compensate": (["compensate", "{model}", "{desired}"], "desired"),
    "fit": (["fit", "{loop}"], "loop"),
    "export-own-model": (["export", "{model}", "--flat"], "model"),
    "export-c": (["export", "{model}", "--c"], "model"),
    "track": (["track", "{model}", "{desired}", "--plant", "paper-beam"], "desired"),
    "validate-figure": (["validate", "{model}", "{loop}", "--figure"], "loop"),
    "rig-record-voltages": (["rig", "record", "--config", RIG, "--voltages", "{volts}"],
                            "volts"),
    "rig-record-config": (["rig", "record", "--config", "{config}"], "config"),
}


def _inputs(tmp_path):
    files = {"model": GOOD_MODEL, "volts": VOLTS, "desired": DESIRED, "loop": LOOP,
             "config": RIG}
    out = {}
    for key, src in files.items():
        dst = tmp_path / os.path.basename(src)
        shutil.copy(src, dst)
        out[key] = str(dst)
    return out


def _argv(template, inputs, output):
    argv = [a.format(**inputs) if "{" in a else a for a in template]
    if argv[-1] == "--figure":
        return [*argv, output]
    return [*argv, "-o", output]


@pytest.mark.parametrize("how", ["same", "symlink", "hardlink"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_an_output_over_an_input_is_refused(tmp_path, case, how):
    template, victim = CASES[case]
    inputs = _inputs(tmp_path)
    with open(inputs[victim], "rb") as f:
        before = f.read()
    suffix = ""
    if case == "validate-figure":
        # --figure wants an image name: the record is given under one
        os.rename(inputs[victim], str(tmp_path / "loop.png"))
        inputs[victim] = str(tmp_path / "loop.png")
        suffix = ".png"
    target = inputs[victim]
    if how == "symlink":
        target = str(tmp_path / f"link{suffix}")
        os.symlink(inputs[victim], target)
    elif how == "hardlink":
        target = str(tmp_path / f"hard{suffix}")
        os.link(inputs[victim], target)
    outcome = run(_argv(template, inputs, target))
    assert outcome.status == 2, outcome.err
    lines = outcome.err.strip().splitlines()
    assert len(lines) == 1 and "refusing to overwrite an input" in lines[0], lines
    with open(inputs[victim], "rb") as f:
        assert f.read() == before


def test_a_report_folder_holding_its_input_is_refused(tmp_path):
    shutil.copy(LOOP, tmp_path / "loop.csv")
    outcome = run(["report", str(tmp_path / "loop.csv"), "--out", str(tmp_path)])
    assert outcome.status == 2 and "holds the input" in outcome.err


@pytest.mark.parametrize("command", [["predict", GOOD_MODEL, VOLTS, "-o"],
                                     ["simulate", "-o"], ["fit", LOOP, "-o"],
                                     ["validate", GOOD_MODEL, LOOP, "--figure"]])
def test_an_empty_output_name_names_the_option(command):
    outcome = run([*command, ""])
    assert outcome.status == 2
    option = command[-1]
    assert outcome.err.strip() == f"pihyst: error: argument {option}: an empty file name ('')"


def test_dev_null_may_be_input_and_output(tmp_path):
    outcome = run(["simulate", "--cycles", "1", "-o", os.devnull])
    assert outcome.status == 0, outcome.err
