"""Scenario texts shared by the command-line tests."""

SMALL_AXIS = """\
[simulation]
t_after = 0.5

[move]
distance = 0.3
v_max = 2.0
a_max = 4.0

[z]
distance = 0.3
a_max = 8.0
v_max = 2.0

[[mode]]
zeta = 0.04
law = "linear"
z = [0.0, 0.5]
f = [10.5, 7.035]
"""
"""A short Y-like move (0.3 m, no cruise) with Z moving 0.3 m and one linear mode: the
[simulation], [move], [z] and [[mode]] tables of a small scenario, 0.5 s after the motion."""
