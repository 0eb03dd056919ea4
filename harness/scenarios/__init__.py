"""Embedded default scenarios (TOML), run by ``djl-fmu simulate`` with no file given.

See ``docs/harness.md`` for how their numbers were chosen.
"""
