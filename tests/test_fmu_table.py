"""Profile 4, ``table`` (issue 33 item 3): a reference the FMU replays sample by sample.

The jerk ``table_jerk[i]`` is held for ``table_samples[i]`` samples of Te from the motion's
start at ``x0``; x, v, a are the exact piecewise cubic, the table ends at rest at
``x0 + distance`` (docs/generator.md, "Replayed tables").  Checked here, independently of
the C code:

- every output against the table's piecewise cubic evaluated in exact rational arithmetic
  (``fractions.Fraction``, :class:`Exact`), at communication points off the sample grid,
  on tables built here: bang-bang jerk sequences of a few dozen switches that come back
  to rest exactly (a sequence P whose acceleration ends at 0, then -P);
- the end lands exactly on ``x0 + distance``; the FMU (FMI 2 and 3) equals the compiled
  engine bit for bit; a JL move's own per-sample jerk replayed as a table gives the JL
  move; a custom input shaper on a table gives the exact convolution computed here;
- every bad table and every parameter a table does not take is refused by name, the
  instance usable afterwards; a stop or an execute during or after a table comes to rest
  within the limits (a stop no further than the table goes, an execute on its target);
  an FMU state saved mid-table replays bit for bit;
- a property test over random bang-bang tables (the fast engine): lands exactly, outputs
  continuous, limits kept;
- :class:`harness.simulation.jerk_table.JerkTable` and ``Session.run(..., table=...)`` on
  both engines.
"""

from __future__ import annotations

import math
import random
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness import _engine
from harness.fmu import spec
from harness.fmu.runner import REAL_OUTPUTS, FMUError, GeneratorFMU
from harness.scenario import load_scenario
from harness.simulation.jerk_table import JerkTable
from harness.simulation.session import Session

TE = 1e-3


# --------------------------------------------------------------------------- exact reference


class Exact:
    """The table's piecewise cubic in exact rational arithmetic (the test's own integration).

    Piece i starts at sample k_i with (x_i, v_i, a_i) and holds jerk j_i over n_i samples;
    before the start the axis rests at x0 (v0 = 0), after the end at x0 + x_n.
    """

    def __init__(self, samples, jerk, Te=TE, x0=0.0):
        self.Te, self.x0 = Fr(Te), Fr(x0)
        self.n, self.j = list(samples), [Fr(j) for j in jerk]
        self.k, self.x, self.v, self.a = [0], [Fr(0)], [Fr(0)], [Fr(0)]
        self.V = Fr(0)
        for n, j in zip(self.n, self.j, strict=True):
            L, x, v, a = n * self.Te, self.x[-1], self.v[-1], self.a[-1]
            if j != 0 and 0 < -a / j < L:  # the velocity's extremum inside the piece
                s = -a / j
                self.V = max(self.V, abs(v + a * s + j * s * s / 2))
            self.k.append(self.k[-1] + n)
            self.x.append(x + v * L + a * L * L / 2 + j * L ** 3 / 6)
            self.v.append(v + a * L + j * L * L / 2)
            self.a.append(a + j * L)
        self.V = max([self.V] + [abs(v) for v in self.v])
        self.A = max(abs(a) for a in self.a)
        self.X = max(abs(x) for x in self.x)
        self.J = max([abs(j) for j in self.j] + [Fr(0)])

    @property
    def end(self) -> tuple[Fr, Fr, Fr]:
        return self.x[-1], self.v[-1], self.a[-1]

    @property
    def samples_total(self) -> int:
        return self.k[-1]

    def at(self, u: Fr) -> tuple[Fr, Fr, Fr, Fr]:
        """x (absolute), v, a, j at u samples after the start (j right-continuous)."""
        if u < 0:
            return self.x0, Fr(0), Fr(0), Fr(0)
        i = max(i for i in range(len(self.k)) if self.k[i] <= u)
        if i == len(self.n):
            return self.x0 + self.x[-1], self.v[-1], Fr(0), Fr(0)
        s = (u - self.k[i]) * self.Te
        x, v, a, j = self.x[i], self.v[i], self.a[i], self.j[i]
        return (self.x0 + x + v * s + a * s * s / 2 + j * s ** 3 / 6, v + a * s + j * s * s / 2,
                a + j * s, j)

    def limits(self, margin: float = 0.0, sign: int = 1) -> dict[str, float]:
        """v_max, a_max, d_max just above (margin: relative) what the table reaches."""
        up = max([sign * a for a in self.a] + [Fr(0)])
        down = max([-sign * a for a in self.a] + [Fr(0)])
        m = 1.0 + margin
        return {"v_max": float(self.V) * m or 1.0, "a_max": float(up) * m or 1.0,
                "d_max": float(down) * m or 1.0}


def bang_bang(rng: random.Random, switches: int, J: float, *, notch: bool = True,
              cruise: bool = True, n_max: int = 40) -> tuple[list[int], list[float]]:
    """A bang-bang jerk (values +-J and, with cruise, 0) that comes back to rest exactly.

    P alternates +J and -J over lengths whose sums are equal, so that its acceleration
    ends at 0; -P then brings the velocity back to 0 (its velocity change is -P's
    opposite).  Without notch the acceleration of P stays >= 0 (each +J piece followed by a
    -J piece of the same length): the velocity rises through P and falls through -P, the
    axis never backs up.
    """
    pieces: list[tuple[int, float]] = []
    half = max(1, switches // 4)
    if notch:
        plus = [rng.randint(1, n_max) for _ in range(half)]
        total = sum(plus)
        if total > half:  # another composition of the same total into half parts
            cuts = sorted(rng.sample(range(1, total), half - 1))
            minus = [b - a for a, b in zip([0, *cuts], [*cuts, total], strict=True)]
        else:
            minus = plus[::-1]
        for p, m in zip(plus, minus, strict=True):
            pieces.append((p, J))
            if cruise and rng.random() < 0.5:
                pieces.append((rng.randint(1, n_max), 0.0))
            pieces.append((m, -J))
    else:
        for _ in range(half):
            p = rng.randint(1, n_max)
            pieces.append((p, J))
            if cruise and rng.random() < 0.5:
                pieces.append((rng.randint(1, n_max), 0.0))
            pieces.append((p, -J))
            if cruise and rng.random() < 0.5:
                pieces.append((rng.randint(1, n_max), 0.0))
    table = pieces + [(n, -j) for n, j in pieces]
    return [n for n, _ in table], [j for _, j in table]


def params_of(samples, jerk, *, margin=0.0, x0=0.0, sign=1, **extra):
    """Parameters of a table: distance its exact end, limits just above what it reaches."""
    jerk = [sign * j for j in jerk]
    ex = Exact(samples, jerk, TE, x0)
    p = {"profile": 4, "Te": TE, "x0": x0, "distance": float(ex.end[0]), "table_n": len(samples),
         "table_samples": list(samples), "table_jerk": list(jerk),
         **ex.limits(margin, 1 if ex.end[0] >= 0 else -1)}
    p.update(extra)
    return p, ex


def random_table(seed: int, switches: int = 32, *, notch: bool = True, J: float = 150.0):
    rng = random.Random(seed)
    return bang_bang(rng, switches, J, notch=notch)


def scale_of(ex: Exact, x0: float = 0.0) -> dict[str, float]:
    return {"x": float(ex.X) + abs(x0), "v": float(ex.V), "a": float(ex.A), "j": float(ex.J)}


# --------------------------------------------------------------------------- replay


@pytest.mark.parametrize("seed", [1, 2])
def test_table_is_replayed_exactly_at_any_communication_time(fmu, seed):
    """x, v, a, j at communication points off the sample grid are the exact piecewise cubic
    (to 1e-12 of each quantity's scale); the end lands exactly on x0 + distance."""
    samples, jerk = random_table(seed, 36)
    p, ex = params_of(samples, jerk, margin=0.01, x0=0.125, t_start=0.0123)
    sc = scale_of(ex, 0.125)
    rng = random.Random(seed)
    start = math.ceil(0.0123 / TE - 1e-9) * TE  # the first sample at or after t_start
    with GeneratorFMU(fmu, params=p) as g:
        g.initialize()
        assert g.get("motion_time") == ex.samples_total * TE
        assert [g.get(f"N_F{i}") for i in range(1, 5)] == [80, 80, 60, 50]  # T_F1..4's
        assert g.get("v_reached") == pytest.approx(float(ex.V), rel=1e-12)
        vr = g.vr(("x", "v", "a", "j"))
        t, checked = 0.0, 0
        while t < start + (ex.samples_total + 20) * TE:
            h = rng.uniform(0.05, 9.7) * TE
            g.do_step(h)
            t = g.time
            u = (Fr(t) - Fr(start)) / Fr(TE)
            want = ex.at(u)
            got = g.get_reals(vr)
            for name, w, y in zip("xvaj", want, got, strict=True):
                if name == "j" and abs(u - round(u)) < Fr(1, 10**6):
                    continue  # on a piece boundary: either side's jerk
                assert abs(y - float(w)) <= 1e-12 * sc[name], (name, t, y, float(w))
            checked += 1
        assert checked > 100
        # at rest exactly on the target, done
        x, v, a, j = g.get_reals(vr)
        assert (x, v, a, j) == (0.125 + p["distance"], 0.0, 0.0, 0.0)
        assert g.get("done") and not g.get("busy")
        assert g.get("stage") == 0 and g.get("segment") == 1


def test_motion_starts_at_the_first_sample_at_or_after_t_start(fmu2):
    samples, jerk = random_table(3, 8)
    p, ex = params_of(samples, jerk, t_start=0.0104)
    with GeneratorFMU(fmu2, params=p, start_time=0.0003) as g:
        g.initialize()
        t, y = g.record(40, TE, ("x", "v", "j"))
    # the grid is 0.0003 + k Te: the first sample at or after 0.0104 is 0.0113
    k0 = int(np.argmax(y["j"] != 0.0))
    assert t[k0] == pytest.approx(0.0113, abs=1e-15)
    assert y["j"][k0] == jerk[0] and np.all(y["x"][:k0] == 0.0)


@pytest.mark.parametrize("sign", [1, -1])
def test_limits_are_mirrored_for_a_move_backwards(fmu2, sign):
    """a_max and d_max differ; a table that speeds up at a_max and slows down at d_max is
    accepted forwards, and mirrored (jerk negated, distance < 0) backwards; swapping the
    limits refuses it, naming a piece and the acceleration reached."""
    # a bump of +-300 m/s3 over (10, 10, 10) samples speeds up at 3 m/s2 to 0.06 m/s, one of
    # -+j_dn over (14, 10, 14) slows down at 14 j_dn Te = 2.5 m/s2 back to rest
    samples = [10, 10, 10, 20, 14, 10, 14]
    v_up = Fr(300) * (10 * Fr(TE)) * (20 * Fr(TE))
    j_dn = v_up / ((14 * Fr(TE)) * (24 * Fr(TE)))
    jerk = [300.0, 0.0, -300.0, 0.0, -float(j_dn), 0.0, float(j_dn)]
    p, ex = params_of(samples, jerk, sign=sign)
    assert abs(float(ex.end[1])) < 1e-15 and abs(float(ex.end[2])) < 1e-9
    a_up, a_dn = 3.0, float(j_dn * 14 * Fr(TE))
    assert a_dn == pytest.approx(2.5, rel=1e-15)
    p.update(v_max=1.0, a_max=a_up * 1.000001, d_max=a_dn * 1.000001)
    with GeneratorFMU(fmu2, params=p) as g:
        g.initialize()
        t, y = g.record(100, TE, ("x", "a"))
    assert y["x"][-1] == p["distance"] and sign * p["distance"] > 0
    # speeding up at a_max, slowing down at d_max, in the direction of the move
    assert (sign * y["a"]).max() == pytest.approx(a_up, rel=1e-12)
    assert (-sign * y["a"]).max() == pytest.approx(a_dn, rel=1e-12)
    p.update(a_max=a_dn * 1.000001, d_max=a_up * 1.000001)
    with GeneratorFMU(fmu2, params=p) as g:
        with pytest.raises(FMUError) as e:
            g.initialize()
    msg = str(e.value)
    assert "table_jerk[1] = " in msg and "the table's acceleration is" in msg, msg
    assert ("a move forwards" if sign > 0 else "a move backwards") in msg


def test_an_empty_table_rests_at_x0(fmu2):
    with GeneratorFMU(fmu2, params={"profile": 4, "table_n": 0, "distance": 0.0,
                                    "x0": -0.25}) as g:
        g.initialize()
        assert g.get("motion_time") == 0.0
        t, y = g.record(5, TE, ("x", "v"), ("done",))
    assert np.all(y["x"] == -0.25) and np.all(y["v"] == 0.0) and y["done"].all()


def test_fast_engine_equals_the_fmu_bit_for_bit(fmus):
    samples, jerk = random_table(4, 40)
    cases = [params_of(samples, jerk, margin=0.002)[0],
             params_of(samples, jerk, sign=-1, x0=1.5, t_start=0.0217)[0]]
    shaper = {"shaper": 4, "shaper_n": 3, "shaper_amplitude": [0.25, 0.5, 0.25],
              "shaper_delay": [0.0, 0.0314, 0.0628]}
    cases.append(dict(cases[0], **shaper))
    cases.append(dict(cases[1], shaper=2, f_shaper=7.0))
    for p in cases:
        pl = _engine.plan(p, 0.002)
        n = int(round(pl.motion_time / TE)) + 60
        out = np.empty((_engine.N_SAMPLE_VARS, n + 1))
        pl.sample_into(out, 0, 1, n + 1)
        for v in (2, 3):
            with GeneratorFMU(fmus[v], params=p, start_time=0.002) as g:
                g.initialize()
                _, y = g.record(n, TE, REAL_OUTPUTS)
                assert g.get("motion_time") == pl.motion_time
            for i, k in enumerate(REAL_OUTPUTS):
                np.testing.assert_array_equal(out[i], y[k], err_msg=f"FMI {v}: {k}")
        assert out[0, -1] == p.get("x0", 0.0) + p["distance"]


def test_a_table_of_256_pieces(fmus):
    """The capacity, DJL_MAX_TABLE: 256 pieces in both FMUs and the engine, bit for bit,
    each piece's jerk its entry's, landing exactly; 257 entries are refused (BAD below)."""
    rng = random.Random(11)
    P = []
    for _ in range(64):
        n = rng.randint(1, 9)
        P += [(n, 500.0), (n, -500.0)]
    samples = [n for n, _ in P] * 2
    jerk = [j for _, j in P] + [-j for _, j in P]
    assert len(samples) == spec.MAX_TABLE
    p, ex = params_of(samples, jerk, margin=0.001)
    pl = _engine.plan(p)
    n = ex.samples_total + 5
    out = np.empty((_engine.N_SAMPLE_VARS, n))
    pl.sample_into(out, 0, 1, n)
    np.testing.assert_array_equal(out[3, : ex.samples_total], np.repeat(jerk, samples))
    assert out[0, -1] == p["distance"]
    for v in (2, 3):
        with GeneratorFMU(fmus[v], params=p) as g:
            g.initialize()
            assert g.get("table_n") == 256 and list(g.get("table_samples")) == samples
            _, y = g.record(n - 1, TE, ("x", "v", "a", "j"))
        for i, k in enumerate("xvaj"):
            np.testing.assert_array_equal(y[k], out[i], err_msg=f"FMI {v}: {k}")


def test_jl_moves_own_jerk_replayed_as_a_table_is_the_jl_move(fmu):
    """The per-sample jerk of a JL move (the FMU's own output), run-length encoded, replayed
    as a table: the same x, v, a at every sample (to rounding) and the same jerk (exactly)."""
    jl = {"profile": 2, "Te": TE, "distance": 0.3, "v_max": 0.8, "a_max": 6.0, "d_max": 6.0,
          "T_F1": 0.031}
    with GeneratorFMU(fmu, params=jl) as g:
        g.initialize()
        n = int(round(g.get("motion_time") / TE))
        _, ref = g.record(n + 20, TE, ("x", "v", "a", "j"))
    table = JerkTable.from_jerk_samples(ref["j"][:n], TE)
    assert 5 <= len(table) <= 9  # 4 ramps, the plateaus between them
    x_end, v_end, a_end = table.end_state(TE)
    assert abs(x_end - 0.3) < 1e-12 and abs(v_end) < 1e-12 and abs(a_end) < 1e-12
    p = {"Te": TE, "distance": 0.3, "v_max": 0.8, "a_max": 6.0, "d_max": 6.0,
         **table.fmu_parameters()}
    with GeneratorFMU(fmu, params=p) as g:
        g.initialize()
        assert g.get("motion_time") == n * TE
        _, y = g.record(n + 20, TE, ("x", "v", "a", "j"))
    np.testing.assert_array_equal(y["j"], ref["j"])
    for k, tol in (("x", 1e-13), ("v", 1e-12), ("a", 1e-11)):
        np.testing.assert_allclose(y[k], ref[k], rtol=0, atol=tol, err_msg=k)
    # the table lands exactly on the distance, the JL move to its planner's rounding
    assert y["x"][-1] == 0.3 and abs(ref["x"][-1] - 0.3) <= 1e-15


@pytest.mark.parametrize("delays", [[0.0, 0.021, 0.042], [0.0037, 0.0191, 0.0456]],
                         ids=["on the grid", "off the grid"])
def test_custom_shaper_on_a_table_is_the_exact_convolution(fmu, delays):
    """y(t) = sum A_i p(t - t_i) for x, v, a, j: the shaper works on a table's plan as on
    any plan (weighted copies of it), a negative amplitude included."""
    samples, jerk = random_table(5, 24)
    p, ex = params_of(samples, jerk)
    A = [0.5, -0.125, 0.625]
    p.update(shaper=4, shaper_n=3, shaper_amplitude=A, shaper_delay=delays)
    sc = scale_of(ex)
    rng = random.Random(9)
    with GeneratorFMU(fmu, params=p) as g:
        g.initialize()
        assert g.get("motion_time") == pytest.approx(ex.samples_total * TE + delays[-1],
                                                     rel=1e-15)
        vr = g.vr(("x", "v", "a", "j"))
        end = ex.samples_total * TE + delays[-1]
        while g.time < end + 0.01:
            g.do_step(rng.uniform(0.1, 7.3) * TE)
            u = Fr(g.time) / Fr(TE)
            want = [Fr(0)] * 4
            near = False
            for Ai, ti in zip(A, delays, strict=True):
                ui = u - Fr(ti) / Fr(TE)
                near |= abs(ui - round(ui)) < Fr(1, 10**6)
                want = [w + Fr(Ai) * c for w, c in zip(want, ex.at(ui), strict=True)]
            got = g.get_reals(vr)
            for name, w, y in zip("xvaj", want, got, strict=True):
                if name == "j" and near:
                    continue
                assert abs(y - float(w)) <= 1e-12 * 2 * sc[name], (name, g.time, y, float(w))
        assert tuple(g.get_reals(vr)) == (p["distance"], 0.0, 0.0, 0.0)


# --------------------------------------------------------------------------- refusals


def _good() -> dict:
    samples, jerk = random_table(6, 12)
    return params_of(samples, jerk, margin=0.01)[0]


GOOD = _good()


def _edit(**changes):
    p = dict(GOOD, table_samples=list(GOOD["table_samples"]),
             table_jerk=list(GOOD["table_jerk"]))
    for k, v in changes.items():
        if isinstance(v, tuple):  # (index, value) of an array
            p[k][v[0]] = v[1]
        else:
            p[k] = v
    return p


BAD = [
    (_edit(table_n=-1), "table_n = -1"),
    (_edit(table_n=257), "table_n = 257"),
    (_edit(table_samples=(2, 0)), "table_samples[3] = 0"),
    (_edit(table_samples=(0, -4)), "table_samples[1] = -4"),
    (_edit(table_samples=(1, 100000001)), "table_samples[2] = 100000001"),
    (_edit(table_jerk=(3, float("nan"))), "table_jerk[4] = nan"),
    (_edit(table_jerk=(0, float("inf"))), "table_jerk[1] = inf"),
    (_edit(table_jerk=(0, -float("inf"))), "table_jerk[1] = -inf"),
    (_edit(table_jerk=(1, 2.5e4), a_max=10.0, d_max=10.0), "beyond (a_max + d_max) / Te"),
    # a jerk within its bound whose piece leaves the doubles (pieces of 10^200 s)
    (_edit(Te=1e200, T_F1=1e200, T_F2=1e200, T_F3=1e200, T_F4=1e200, table_jerk=(0, 1e-200)),
     "the position at the end of piece 1"),
    # the end: not at rest (the acceleration, the velocity), not on the distance
    (_edit(table_n=GOOD["table_n"] - 1), "not at rest"),
    (_edit(table_n=GOOD["table_n"] // 2), "not at rest"),
    (_edit(distance=GOOD["distance"] * (1 + 1e-8)), "distance = "),
    # the limits
    (_edit(v_max=GOOD["v_max"] * 0.99), "beyond v_max"),
    (_edit(a_max=GOOD["a_max"] * 0.99), "the table's acceleration is"),
    (_edit(d_max=GOOD["d_max"] * 0.99), "the table's acceleration is"),
    # what a table does not take
    (_edit(n_segments=2, seg_distance=[0.1, 0.1]), "n_segments = 2 with profile = 4"),
    (_edit(v_e=0.1), "v_e = 0.1 m/s with profile = 4"),
    (_edit(T_F3=1e-4), "T_F3 = 0.0001 s rounds to 0 samples"),
]


@pytest.mark.parametrize("bad, text", BAD, ids=[t for _, t in BAD])
def test_bad_tables_are_refused_by_name(fmu, bad, text):
    with GeneratorFMU(fmu, params=bad) as g:
        with pytest.raises(FMUError, match=r"ExitInitializationMode") as e:
            g.initialize()
        assert text in str(e.value), str(e.value)
        assert "invalid parameter" in str(e.value)
        # the instance is in the Error state (getters only); a reset makes it usable again
        g.replan(GOOD)
        _, y = g.record(int(round(g.get("motion_time") / TE)) + 2, TE, ("x",))
        assert y["x"][-1] == GOOD["distance"]
    # the compiled engine refuses them with the same message
    with pytest.raises(_engine.PlanError) as e2:
        _engine.plan(bad)
    assert text in str(e2.value)


@pytest.mark.parametrize("source", [2, 3])
def test_jerk_times_from_f_mode_are_refused_for_a_table(fmu, source):
    with GeneratorFMU(fmu, params=dict(GOOD, jerk_source=source)) as g:
        with pytest.raises(FMUError) as e:
            g.initialize()
    assert f"jerk_source = {source} with profile = 4 (table)" in str(e.value)


def test_the_fmi2_integer_alias_takes_4(fmu2):
    p = dict(GOOD)
    del p["profile"]
    with GeneratorFMU(fmu2, params=dict(p, profile_code=4)) as g:
        g.initialize()
        assert g.get("profile") == 4 and g.get("motion_time") > 0
    with GeneratorFMU(fmu2, params=dict(p, profile_code=5)) as g, pytest.raises(FMUError) as e:
        g.initialize()
    assert "profile = 5: must be 1 (AL), 2 (JL), 3 (DJL) or 4 (table)" in str(e.value)


def test_the_model_descriptions_declare_the_table(fmus):
    from fmpy import read_model_description

    assert ("table", 4, "piecewise-constant jerk replayed from table_samples / table_jerk") \
        in spec.ENUMERATIONS["Profile"]
    for v, path in fmus.items():
        md = read_model_description(str(path))
        names = {x.name: x for x in md.modelVariables}
        assert names["profile"].max == "4"
        if v == 2:
            assert names["profile_code"].max == "4"
            assert names["table_samples[256]"].valueReference == 1255
            assert names["table_jerk[1]"].valueReference == 2000
            assert names["table_samples[1]"].type == "Integer"
        else:
            assert names["table_samples"].type == "Int32"
            assert int(names["table_jerk"].dimensions[0].start) == 256
        assert names["table_n"].max == "256"


# --------------------------------------------------------------------------- commands, states


def _run_commanded(fmu, p, at, command, n_after=2500):
    """Step by Te; at sample ``at`` set the command; return the record."""
    with GeneratorFMU(fmu, params=p, debug_logging=True) as g:
        g.initialize()
        total = int(round(g.get("motion_time") / TE)) + n_after

        def inputs(k):
            return dict(command) if k >= at else {}

        t, y = g.record(total, TE, ("x", "v", "a", "j"), ("done",), inputs=inputs)
        log = list(g.log)
    return t, y, log


@pytest.mark.parametrize("frac", [0.05, 0.3, 0.55, 0.8, 0.9, 0.97, 1.2])
def test_a_stop_during_a_table_rests_within_the_limits_and_the_table(fmu, frac):
    """A stop at any time (a monotone table: the axis never backs up): at rest, within v_max
    and a_max/d_max, between the position at the stop and the table's target."""
    samples, jerk = random_table(7, 28, notch=False)
    p, ex = params_of(samples, jerk, margin=0.0)
    at = int(frac * ex.samples_total)
    t, y, log = _run_commanded(fmu, p, at, {"stop": True})
    assert y["done"][-1] and y["v"][-1] == 0.0 and y["a"][-1] == 0.0
    tol = 1 + 1e-9
    assert np.abs(y["v"]).max() <= p["v_max"] * tol
    assert y["a"].max() <= p["a_max"] * tol and -y["a"].min() <= p["d_max"] * tol
    assert y["v"].min() >= -1e-12 * p["v_max"]  # never backs up
    x_stop = y["x"][at]
    assert x_stop - 1e-15 <= y["x"][-1] <= p["distance"] + 1e-12 * p["distance"]
    kept = any("the move is kept" in r.message for r in log)
    if frac > 1.0:  # after the end: it stays where it is
        assert y["x"][-1] == p["distance"] and not kept
    if frac == 0.9:
        # in the table's own last deceleration, sharper than a stop's stages (T_F3, T_F4): a
        # stop would rest past the target, so the table is kept and lands on it (the table
        # rests at its target before its end: without the table's rule in djl_replan.c's
        # stop_passes, that rest made the target no bound and such stops passed it)
        assert kept and y["x"][-1] == p["distance"]
    assert not [r for r in log if r.status >= 3]


def test_a_stop_on_a_table_that_turns_back_is_made(fmu2):
    """A table whose velocity dips below 0 inside a piece (it backs up, then goes on): its
    target bounds nothing, the stop is made, at rest within the limits."""
    samples = [18, 38, 40, 20, 18, 18]
    jerk = [100.0, -100.0, 100.0, -100.0, -100.0, 100.0]
    p, ex = params_of(samples, jerk)
    v3 = ex.v[2]  # piece 3: a from -2 to 2 m/s2, v from 0.0124 m/s down to -0.0076 and back
    assert v3 > 0 and ex.v[3] > 0 and float(v3 - Fr(2) ** 2 / 200) < -0.007
    p.update(v_max=0.04, a_max=2.1, d_max=2.1)
    t, y, log = _run_commanded(fmu2, p, 30, {"stop": True})
    assert y["done"][-1] and y["v"][-1] == 0.0
    assert np.abs(y["v"]).max() <= 0.04 and np.abs(y["a"]).max() <= 2.1
    assert not any("the move is kept" in r.message for r in log)
    assert any("stop: replanned" in r.message for r in log)


@pytest.mark.parametrize("frac, target", [(0.1, 0.05), (0.4, -0.2), (0.5, 2.0), (0.9, 0.3),
                                          (1.1, -0.4)])
def test_an_execute_during_a_table_lands_on_its_target(fmu, frac, target):
    """An execute replaces the table by a move (stages of T_F1..T_F4) from wherever the axis
    is, at any velocity and acceleration: it lands exactly on the target, within the
    limits."""
    samples, jerk = random_table(8, 28)
    p, ex = params_of(samples, jerk, margin=0.0)
    at = int(frac * ex.samples_total)
    t, y, log = _run_commanded(fmu, p, at, {"target": target, "execute": True}, 4000)
    assert y["done"][-1] and y["v"][-1] == 0.0 and y["a"][-1] == 0.0
    assert abs(y["x"][-1] - target) <= 1e-12 * (abs(target) + float(ex.X))
    tol = 1 + 1e-9
    assert np.abs(y["v"]).max() <= p["v_max"] * tol
    assert np.abs(y["a"]).max() <= max(p["a_max"], p["d_max"]) * tol
    np.testing.assert_array_equal(y["x"][: at + 2], _run_commanded(fmu, p, 10**9, {})[1]["x"]
                                  [: at + 2])  # nothing changes up to the command's sample
    assert not [r for r in log if r.status >= 3]


def test_state_saved_mid_table_replays_bit_for_bit(fmu):
    samples, jerk = random_table(9, 30)
    p, ex = params_of(samples, jerk, margin=0.05)
    p.update(shaper=1, f_shaper=9.0)
    names = ("x", "v", "a", "j")
    with GeneratorFMU(fmu, params=p) as g:
        g.initialize()
        for _ in range(ex.samples_total // 3):
            g.do_step(TE)
        t0 = g.time
        state = g.get_state()

        def inputs(k):
            return {"stop": True} if k == 150 else {}

        _, first = g.record(900, TE, names, ("done",), inputs=inputs)
        data = g.serialize_state(state)
        g.free_state(state)
        back = g.deserialize_state(data)
        g.set_state(back, t0)
        g.free_state(back)
        _, again = g.record(900, TE, names, ("done",), inputs=inputs)
    for k in (*names, "done"):
        np.testing.assert_array_equal(again[k], first[k], err_msg=k)
    assert first["done"][-1]


# --------------------------------------------------------------------------- properties


@st.composite
def tables(draw):
    seed = draw(st.integers(0, 2**31))
    switches = draw(st.integers(2, 48))
    J = draw(st.sampled_from([1.0, 37.5, 400.0, 1e4]))
    notch = draw(st.booleans())
    n_max = draw(st.sampled_from([1, 3, 40, 500]))
    rng = random.Random(seed)
    samples, jerk = bang_bang(rng, switches, J, notch=notch, n_max=n_max)
    margin = draw(st.sampled_from([0.0, 1e-6, 0.5]))
    x0 = draw(st.sampled_from([0.0, -0.37, 1e3]))
    sign = draw(st.sampled_from([1, -1]))
    return params_of(samples, jerk, margin=margin, x0=x0, sign=sign)


@settings(max_examples=60)
@given(tables())
def test_random_bang_bang_tables_land_exactly_continuously_within_the_limits(case):
    p, ex = case
    pl = _engine.plan(p)
    n = ex.samples_total
    assert pl.k_end == n and pl.motion_time == n * TE
    out = np.empty((_engine.N_SAMPLE_VARS, n + 3))
    pl.sample_into(out, 0, 1, n + 3)
    x, v, a, j = out[:4]
    x0 = p["x0"]
    # lands exactly, at rest
    assert x[n] == x0 + p["distance"] and v[n] == 0.0 and a[n] == 0.0 and j[n] == 0.0
    assert np.all(x[n:] == x[n])
    # limits (the table's own, up to the FMU's tolerance)
    s = 1.0 if p["distance"] >= 0 else -1.0
    tol = 1 + 1e-9
    assert np.abs(v).max() <= p["v_max"] * tol
    assert (s * a).max() <= p["a_max"] * tol and (-s * a).max() <= p["d_max"] * tol
    # continuous: each sample is the cubic of the one before it (and the jerk the table's)
    L = TE
    x1 = x[:-1] + L * (v[:-1] + L * (0.5 * a[:-1] + L * j[:-1] / 6.0))
    v1 = v[:-1] + L * (a[:-1] + 0.5 * L * j[:-1])
    a1 = a[:-1] + L * j[:-1]
    sc = scale_of(ex, x0)
    assert np.abs(x1 - x[1:]).max() <= 1e-9 * sc["x"] + 1e-300
    assert np.abs(v1 - v[1:]).max() <= 1e-9 * sc["v"] + 1e-300
    assert np.abs(a1 - a[1:]).max() <= 1e-9 * sc["a"] + 1e-300
    want_j = np.repeat(np.array(p["table_jerk"]), p["table_samples"])
    np.testing.assert_array_equal(j[:n], want_j)
    # and the exact cubic at a few samples
    for k in (n // 3, n // 2, n - 1):
        for i, w in enumerate(ex.at(Fr(k))[:3]):
            assert abs(out[i, k] - float(w)) <= 1e-12 * sc["xva"[i]]


# --------------------------------------------------------------------------- harness side


def test_jerk_table_checks_its_entries():
    with pytest.raises(ValueError, match="as many samples as jerks"):
        JerkTable((1, 2), (0.0,))
    with pytest.raises(ValueError, match=r"samples\[1\] = 0"):
        JerkTable((3, 0), (1.0, 2.0))
    with pytest.raises(ValueError, match=r"samples\[0\] = 2.0"):
        JerkTable((2.0,), (1.0,))
    with pytest.raises(ValueError, match=r"jerk\[0\] = nan"):
        JerkTable((2,), (float("nan"),))
    with pytest.raises(ValueError, match="at most 256 pieces"):
        JerkTable((1,) * 257, (0.0,) * 257)
    t = JerkTable([np.int64(3), 4], [np.float64(1.5), -2])
    assert t.samples == (3, 4) and t.jerk == (1.5, -2.0) and len(t) == 2
    assert type(t.samples[0]) is int and type(t.jerk[1]) is float
    assert t.fmu_parameters() == {"profile": 4, "table_n": 2, "table_samples": [3, 4],
                                  "table_jerk": [1.5, -2.0]}
    assert t.motion_time(2e-3) == 7 * 2e-3
    with pytest.raises(ValueError, match="Te must be"):
        t.motion_time(0.0)


def test_from_jerk_samples_encodes_runs_and_keeps_the_end():
    j = [5.0] * 3 + [5.0 * (1 + 1e-14)] * 2 + [0.0] * 4 + [-5.0, -5.0 * (1 - 1e-13)] + [7.0]
    t = JerkTable.from_jerk_samples(j, TE)
    assert t.samples == (5, 4, 2, 1)
    assert t.jerk[1:] == (0.0, math.fsum([-5.0, -5.0 * (1 - 1e-13)]) / 2, 7.0)
    assert t.jerk[0] == pytest.approx(5.0, rel=1e-14)
    # exactly equal runs keep their exact value
    assert JerkTable.from_jerk_samples([0.1] * 7, TE).jerk == (0.1,)
    # rtol = 0: only equal values merge
    assert JerkTable.from_jerk_samples(j, TE, rtol=0.0).samples == (3, 2, 4, 1, 1, 1)
    # the end state: that of the samples, computed here in exact arithmetic
    ex = Exact([1] * len(j), j)
    for got, want in zip(t.end_state(TE), ex.end, strict=True):
        assert abs(got - float(want)) <= 1e-15
    with pytest.raises(ValueError, match=r"jerk_per_sample\[2\] = inf"):
        JerkTable.from_jerk_samples([0.0, 1.0, float("inf")], TE)
    with pytest.raises(ValueError, match="more than the 256 pieces"):
        JerkTable.from_jerk_samples(np.arange(300.0), TE)
    with pytest.raises(ValueError, match="rtol"):
        JerkTable.from_jerk_samples(j, TE, rtol=0.1)
    assert JerkTable.from_jerk_samples([], TE).samples == ()


def test_end_state_and_extremes_are_the_exact_ones():
    samples, jerk = random_table(10, 20)
    t = JerkTable(tuple(samples), tuple(jerk))
    ex = Exact(samples, jerk)
    for got, want in zip(t.end_state(TE), ex.end, strict=True):
        assert abs(got - float(want)) <= 1e-14 * float(ex.X + ex.V + ex.A)
    for got, want in zip(t.extremes(TE), (ex.X, ex.V, ex.A), strict=True):
        assert got == pytest.approx(float(want), rel=1e-13)


def test_session_replays_a_table_on_both_engines():
    """Scenario X's JL move, its per-sample jerk as a table: Session.run(..., "table") gives
    the JL run on either engine, and the two engines agree bit for bit."""
    sc = load_scenario("X")
    T_F = (0.06,) * 4
    with Session(engine="fast") as s:
        jl = s.run(sc, "JL", T_F)
        params = s.move_params(sc, "JL", T_F)
        pl = _engine.plan(params)
        n = pl.k_end
        out = np.empty((_engine.N_SAMPLE_VARS, n))
        pl.sample_into(out, int(pl.offset), 1, n)
        table = JerkTable.from_jerk_samples(out[3], sc.simulation.Te)
        fast = s.run(sc, "table", T_F, table=table)
        with pytest.raises(ValueError, match="needs a JerkTable"):
            s.move_params(sc, "table")
        with pytest.raises(ValueError, match="replayed by profile 'table'"):
            s.move_params(sc, "JL", T_F, table=table)
    p = Session.move_params(sc, "table", T_F, table=table)
    assert p["profile"] == 4 and p["table_n"] == len(table) and p["T_F1"] == 0.06
    with Session(engine="fmu", fmi_version=3) as s:
        slow = s.run(sc, "table", T_F, table=table)
    for k in ("x", "v", "a", "j"):
        np.testing.assert_array_equal(getattr(fast, k), getattr(slow, k), err_msg=k)
        np.testing.assert_allclose(getattr(fast, k), getattr(jl, k), rtol=0,
                                   atol=1e-11 * np.abs(getattr(jl, k)).max(), err_msg=k)
    np.testing.assert_allclose(fast.eps, jl.eps, rtol=0, atol=1e-9 * np.abs(jl.eps).max())


def test_engine_replan_refuses_a_table():
    pl = _engine.plan(GOOD)
    with pytest.raises(ValueError, match="a table .profile 4. has its own jerk"):
        pl.replan(0.01, 0.01, 0.01, 0.01)
