"""Embedded example part programs (CSV and G-code), read by :mod:`harness.part_program`.

``pick-place-X.csv`` and ``pick-place-X.nc`` are the same pick-and-place cycle on
scenario X's machine (``harness.part_program.example_program``; ``docs/programs.md``).
"""
