"""djl-fmu: AL / JL / DJL trajectory generator FMU and its co-simulation harness.

The generator is C code packaged as an FMI 2.0 / 3.0 co-simulation FMU
(:mod:`harness.fmu`); the harness steps it with fmpy against python-control
models of a flexible axis.
"""

__version__ = "0.1.0"
