"""pihyst models and compensators as python-control systems (``pip install
'pihyst[control]'``): :func:`model_system` and :func:`compensator_system` return
discrete-time ``control.NonlinearIOSystem`` objects whose states are the operator
states, to interconnect with linear dynamics and simulate with
``control.input_output_response``; :func:`compensator_state` is the compensator's
initial state. Usage: docs/control.md.

Importing this module imports python-control (``import pihyst`` does not).
"""

from pihyst.control._systems import compensator_state, compensator_system, model_system

__all__ = ["compensator_state", "compensator_system", "model_system"]
