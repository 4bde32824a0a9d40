"""Serving an emulated device over a byte stream of the operating system (a
pseudo-terminal, a TCP connection): the bytes a client wrote go to the device as they
would have arrived on its serial line, and its replies go back when it would send them.
"""

import time

from pihyst.rig._clock import WallClock


def answer(device, data, write, bytewise=True):
    """Hand ``data``, just read, to ``device`` (as arrived when its last byte would have,
    at the device's baud rate) and ``write`` its replies when they would be sent: one
    byte a character time apart from the device's ready time, or (``bytewise`` False)
    each reply at once when its last byte would be out. ``write`` raises OSError when the
    other side is gone."""
    char_s = device.char_bits / device.baudrate
    arrived = WallClock.now() + len(data) * char_s
    for when, reply in device.receive(data, arrived):
        chunks = ([(when + (i + 1) * char_s, reply[i:i + 1]) for i in range(len(reply))]
                  if bytewise else [(when + len(reply) * char_s, reply)])
        for due, chunk in chunks:
            wait = due - WallClock.now()
            if wait > 0:
                time.sleep(wait)
            write(chunk)
