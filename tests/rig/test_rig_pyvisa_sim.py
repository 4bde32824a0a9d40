"""The pyvisa-sim files of the ASCII dialects (src/pihyst/rig/sim/*.yaml): opened with
pyvisa-sim, spoken to with plain PyVISA and with pihyst's own drivers (the PyMeasure
Instrument classes on a VISAAdapter), which shows the files answer the drivers' bytes."""

import pytest

pyvisa = pytest.importorskip("pyvisa")
pytest.importorskip("pyvisa_sim")
pytest.importorskip("pymeasure")

from pihyst.rig import KeyenceError  # noqa: E402
from pihyst.rig.pymeasure import (  # noqa: E402
    AsciiHVSupply,
    KeyenceLKG3000,
    KeyenceLKG5000,
)
from pihyst.rig.sim import FILES, library, path  # noqa: E402

SCPI = {"query_command": "MEAS:VOLT?", "output_on_command": "OUTP ON",
        "output_off_command": "OUTP OFF"}


@pytest.fixture
def manager():
    managers = []

    def open_file(name):
        rm = pyvisa.ResourceManager(library(name))
        managers.append(rm)
        return rm
    yield open_file
    for rm in managers:
        rm.close()


def test_the_files_are_in_the_package():
    import os
    for name in FILES:
        assert os.path.isfile(path(name))
    with pytest.raises(ValueError, match="no pyvisa-sim file"):
        path("other.yaml")


def test_keyence_dialogue_with_pyvisa(manager):
    rm = manager("keyence.yaml")
    lk = rm.open_resource("ASRL1::INSTR", read_termination="\r", write_termination="\r")
    assert lk.query("MS,01") == "MS,01,+0012.3456"
    assert lk.query("MS,02") == "MS,02,XXXXXXXX"
    assert lk.query("SIM,-3.25") == "SIM,OK"
    assert lk.query("MS,01") == "MS,01,-0003.2500"
    assert lk.query("MQ") == "ER,..,50"
    g3 = rm.open_resource("ASRL2::INSTR", read_termination="\r", write_termination="\r")
    assert g3.query("M1") == "M1,+01.2345"
    assert g3.query("MS,01") == "ER,..,00"


def test_keyence_files_answer_pihysts_driver():
    sensor = KeyenceLKG5000("ASRL1::INSTR", visa_library=library("keyence.yaml"))
    try:
        assert sensor.displacement == pytest.approx(12.3456)
        sensor.driver.command = "MQ"            # a command the controller does not know
        sensor.driver._request = b"MQ\r"
        with pytest.raises(KeyenceError, match="command error"):
            _ = sensor.reading
    finally:
        sensor.adapter.close()
    g3 = KeyenceLKG3000("ASRL2::INSTR", visa_library=library("keyence.yaml"),
                        config={"output": 2, "scale_um": 1000.0})
    try:
        assert g3.reading.status == "invalid"    # output 2 has no head
    finally:
        g3.adapter.close()


def test_scpi_like_supply_through_pihysts_driver():
    hv = AsciiHVSupply("ASRL1::INSTR", visa_library=library("supplies.yaml"), config=SCPI)
    try:
        hv.voltage_setpoint = 42.5
        hv.output_enabled = True
        assert hv.voltage == pytest.approx(42.5)
        hv.shutdown()
        assert hv.voltage == 0.0
    finally:
        hv.adapter.close()


def test_scpi_like_supply_errors_go_to_the_queue(manager):
    hv = manager("supplies.yaml").open_resource("ASRL1::INSTR", read_termination="\r\n",
                                                write_termination="\r\n")
    hv.write("VOLT 12.50")
    assert hv.query("MEAS:VOLT?") == "12.500"
    hv.write("VOLT 1200.00")                  # beyond the simulated supply's 1000 V
    assert hv.query("MEAS:VOLT?") == "12.500"
    assert hv.query("SYST:ERR?") == '-100,"Command error"'


def test_mdt693b_like_query_dialogue(manager):
    md = manager("supplies.yaml").open_resource("ASRL2::INSTR", read_termination="\r",
                                                write_termination="\r")
    md.write("xvoltage=24.80")
    assert md.read() == "*"
    md.write("xvoltage?")
    assert md.read() == "xvoltage?"           # the echo, then the prompt and the value
    assert md.read() == "*[  24.8]"
    md.write("xvoltage=150.10")               # beyond the MDT693B's 150 V
    assert md.read() == "CMD_ARG_INVALID*"


def test_the_socket_resources_speak_the_same(manager):
    lk = manager("keyence.yaml").open_resource("TCPIP::localhost::9002::SOCKET",
                                               read_termination="\r", write_termination="\r")
    assert lk.query("M1") == "M1,+01.2345"
    md = manager("supplies.yaml").open_resource("TCPIP::localhost::9012::SOCKET",
                                                read_termination="\r", write_termination="\r")
    md.write("xvoltage=12.50")
    assert md.read() == "*"
    md.write("xvoltage?")
    assert (md.read(), md.read()) == ("xvoltage?", "*[  12.5]")
