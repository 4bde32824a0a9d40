"""Parts of the simulated piezo beam (:mod:`pihyst.plant` puts them together).

- :mod:`~pihyst.simbeam.preisach`: Preisach hysteresis with an asymmetric density and a
  reversible part, evaluated exactly through its memory (reversal) stack;
- :mod:`~pihyst.simbeam.boucwen`: Bouc-Wen hysteresis, closed-form along monotone runs;
- :mod:`~pihyst.simbeam.lti`: linear time-invariant parts (creep, beam dynamics) as sums
  of first-order modes, exact for any sample spacing.

None of them is a Prandtl-Ishlinskii model: data from the simulated beam are a fair test
of PI identification.
"""
