"""The rig's constructors name their keywords (help() and IDEs show them), and what they
name reaches what they configure: the PyMeasure instruments' PyVISA settings, the
procedures' Parameters (a procedure of one's own included), Rig.controller's options.
Closing an emulated port twice is quiet, as pyserial's own ports are."""

import inspect

import pytest
from rig_helpers import make_config

from pihyst.rig import Rig, VoltageProgram


def test_closing_an_emulated_port_twice_is_quiet():
    with Rig(make_config()) as rig:
        port = rig.sensor.port
        port.close()
        port.close()
        assert not port.is_open


def test_rig_controller_passes_its_keywords():
    with Rig(make_config()) as rig:
        controller = rig.controller(handle_signals=False, watchdog=False,
                                    stop_requested=lambda: True)
        assert (controller.handle_signals, controller.use_watchdog) == (False, False)
        assert controller.run(VoltageProgram([5.0, 6.0])).reason == "stop requested"


pymeasure = pytest.importorskip("pymeasure")

from pymeasure.experiment import IntegerParameter  # noqa: E402

from pihyst.rig.pymeasure import (  # noqa: E402
    KeyenceLKG5000,
    MDT693BLikeSupply,
    RecordProcedure,
    RigProcedure,
)
from pihyst.rig.pymeasure._instruments import _visa_keywords  # noqa: E402


def test_visa_keywords_are_passed_only_when_given():
    assert _visa_keywords("", None, None, None) == {}
    assert _visa_keywords("@py", 250, {"baud_rate": 9600}, {"query_delay": 0.1}) == {
        "visa_library": "@py", "timeout": 250, "asrl": {"baud_rate": 9600},
        "query_delay": 0.1}


def test_instruments_pass_the_named_visa_settings(monkeypatch):
    seen = {}

    class Adapter:
        def __init__(self, resource, **kwargs):
            seen.update(kwargs, resource=resource)

    import pymeasure.instruments.instrument as instrument_module
    monkeypatch.setattr(instrument_module, "VISAAdapter", Adapter)
    KeyenceLKG5000("ASRL9::INSTR", visa_library="@sim", asrl={"baud_rate": 9600},
                   visa_options={"query_delay": 0.5})
    assert seen["resource"] == "ASRL9::INSTR" and seen["visa_library"] == "@sim"
    assert seen["query_delay"] == 0.5 and seen["timeout"] == 100   # [sensor] timeout_s
    assert seen["asrl"]["baud_rate"] == 9600                         # given: kept
    assert seen["asrl"]["stop_bits"] is not None                     # the configuration's
    seen.clear()
    MDT693BLikeSupply("ASRL8::INSTR", timeout=2000)
    assert seen["timeout"] == 2000
    with pytest.raises(TypeError):
        KeyenceLKG5000("ASRL9::INSTR", read_termination="\r")     # not a keyword of it


def test_procedures_take_their_parameters_as_keywords():
    procedure = RecordProcedure(config="rig.toml", period=60.0, cycles=2)
    assert (procedure.config, procedure.period, procedure.cycles) == ("rig.toml", 60.0, 2)
    assert procedure.u_max == 0.0                                   # left out: its default
    assert list(inspect.signature(RecordProcedure).parameters) == [
        "config", "real_time", "signal", "u_min", "u_max", "period", "cycles"]
    with pytest.raises(TypeError):
        RecordProcedure(perod=60.0)


def test_a_procedure_of_ones_own_takes_its_parameters_as_keywords():
    class Mine(RigProcedure):
        trials = IntegerParameter("Trials", minimum=1, default=5)

    assert "trials" in inspect.signature(Mine).parameters
    mine = Mine(config="rig.toml", trials=3)
    assert (mine.config, mine.trials, mine.real_time) == ("rig.toml", 3, False)
    assert Mine().trials == 5
    with pytest.raises(TypeError, match="'trails'"):
        Mine(trails=3)
