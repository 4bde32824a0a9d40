"""Controller(stop_requested=...): a stop asked for from outside (a GUI's abort button)
ends the run like any other stop: ramp down at the slew limit, 0 V, output off."""

import numpy as np
from rig_helpers import make_config

from pihyst.rig import Rig, VoltageProgram


def test_a_requested_stop_ramps_down_to_zero():
    with Rig(make_config()) as rig:
        asked = []

        def stop_requested():
            asked.append(1)
            return len(asked) > 8       # during the ramp up to 150 V (15 ticks)

        program = VoltageProgram(np.full(100, 150.0))
        result = rig.controller(handle_signals=False, stop_requested=stop_requested).run(
            program)
        st = rig.emulators.supply_state
    assert result.reason == "stop requested" and not result.completed and result.zeroed
    assert st.last_setpoint_V == 0.0 and not st.output_on
    phases = [r.phase for r in result.records]
    assert "run" not in phases and phases[-1] == "shutdown"
    u = result.column("voltage_V")
    assert np.all(np.abs(np.diff(u)) <= 200.0 / 20 + 1e-9) and u.max() == 90.0
