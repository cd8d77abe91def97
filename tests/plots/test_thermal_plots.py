"""Figures of the thermoelastic mesh stiffness and natural frequency (rigtools.plots.thermal).

The figures are checked as objects: axes, labels with units, legends, line counts, and the data
of every line read back from its ``Line2D`` against the model arrays it was drawn from
(:func:`models.thermal.mesh_natural_frequency`, and independently the node-wise
:func:`models.thermal.thermoelastic_mesh_stiffness` summed with the quadrature weights). The
statements of seed 000 that must survive plotting are read off the figures: the line at the
critical gap is flat at the elastic stiffness (Table 5, "unchanged"), below it the stiffness
falls with load and above it rises, and the jammed state (SEED-NOTES 10) is marked, never drawn
as a negative or infinite stiffness. The thermal closure is the seed's hot state under the one
reference-state reading that reproduces ``c* ~ 10 um`` (``tests/models/test_thermal_expansion.py``:
10.58 um, ``c*`` 10.28 um).
"""

import math
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from models.geometry import load_gear_set
from models.thermal import (
    SEED_000_CHI,
    TABLE_6_TORQUES_NM,
    ThermalClosure,
    critical_gap,
    mesh_natural_frequency,
    mesh_natural_frequency_scalar,
    prepare_natural_frequency,
    seed_000_hot_state_closure,
    thermoelastic_mesh_stiffness,
)
from rigtools.plots import (
    FIGURE_WIDTH_IN,
    plot_natural_frequency_vs_load,
    plot_stiffness_vs_load,
    save_png,
    thermal_figures,
)

GEAR_SET = load_gear_set("fzg-c")
PAIR = GEAR_SET.pair
CHI = SEED_000_CHI
SRC = "seed 000"
N_TORQUES = 100  # a coarser grid than the report's, same layout
N_BACKLASH = 6  # 0, c*/2, c*, 2 c*, 40 um, 100 um


@pytest.fixture(scope="module")
def closure():
    return seed_000_hot_state_closure(GEAR_SET)


@pytest.fixture(scope="module")
def c_star(closure):
    return float(critical_gap(closure.total_m, CHI))


@pytest.fixture(scope="module")
def model():
    return prepare_natural_frequency(PAIR)


@pytest.fixture(scope="module")
def figures():
    figs = thermal_figures(n_torques=N_TORQUES)
    for fig in figs.values():
        fig.canvas.draw()  # tick labels and layout are final only after a draw
    return figs


@pytest.fixture(scope="module")
def backlash(c_star):
    return np.array([0.0, 0.5 * c_star, c_star, 2 * c_star, 40e-6, 100e-6])


def lines(ax, prefix):
    """Lines of an axes whose gid starts with ``prefix``, by gid."""
    return {ln.get_gid(): ln for ln in ax.get_lines()
            if (ln.get_gid() or "").startswith(prefix)}


def data(ax, prefix):
    """The data lines ``<prefix>/<i>`` in row order."""
    found = lines(ax, prefix + "/")
    return [found[f"{prefix}/{i}"] for i in range(len(found))]


def jam_edge(model, c_star, c):
    """Torque below which backlash ``c`` is jammed: ``r_b1 (c* - c) max_j k_EP,j / R_j``."""
    return model.base_radius_pinion_m * (c_star - c) * np.max(model.k_EP_N_per_m
                                                              / model.load_share)


# --- structure ---------------------------------------------------------------------------------
def test_two_figures_one_data_axes_each(figures):
    assert set(figures) == {"stiffness", "natural_frequency"}
    for fig in figures.values():
        assert isinstance(fig, Figure)
        assert fig.get_size_inches()[0] == pytest.approx(FIGURE_WIDTH_IN)
        (ax,) = fig.axes
        assert ax.get_xlim() == (0.0, 500.0)
        assert ax.get_ylim()[0] == 0.0


def test_every_axis_names_its_quantity_and_unit(figures):
    (ax_k,) = figures["stiffness"].axes
    (ax_f,) = figures["natural_frequency"].axes
    for ax in (ax_k, ax_f):
        assert ax.get_xlabel() == "pinion torque T (N·m)"
    assert ax_k.get_ylabel() == "mean mesh stiffness k̄, whole face (N/µm)"
    assert ax_f.get_ylabel() == "mesh natural frequency $f_n$ (kHz)"
    (top,) = ax_f.child_axes  # the Table 6 torques, with their unit
    assert top.get_xlabel() == "torques of the seed 000 Table 6 runs (N·m)"
    assert not ax_k.child_axes


def test_titles_and_notes_state_the_closure_and_its_reading(figures):
    for key, fig in figures.items():
        title = fig.subfigs[0].get_suptitle()
        assert title.startswith("FZG-C: ")
        assert "Δ₁+Δ₂ = 10.58 µm" in title and "c* = (1 − χ)(Δ₁+Δ₂) = 10.27 µm" in title, key
        (note,) = [t for t in fig.subfigs[-1].texts if t.get_gid() == "note"]
        text = note.get_text().replace("\n", " ")
        assert "Reference-state reading (SEED-NOTES 8)" in text
        assert "only the flash temperature counted as the flanks' local rise" in text
    (note,) = figures["natural_frequency"].subfigs[-1].texts
    assert "m_e = 0.1857 kg" in note.get_text().replace("\n", " ")


def test_line_counts_and_legend(figures, c_star):
    expected = ["c = 0", "c = c*/2 = 5.137 µm", "c = c* = 10.27 µm", "c = 2c* = 20.55 µm",
                "c = 40 µm", "c = 100 µm", "jammed (c < c*): not drawn,\nformula not valid"]
    for fig, prefix in ((figures["stiffness"], "k"), (figures["natural_frequency"], "fn")):
        (ax,) = fig.axes
        assert len(data(ax, prefix)) == N_BACKLASH
        # one jam edge per backlash below c*, none at or above it
        assert sorted(lines(ax, "jam-edge")) == ["jam-edge/0/0", "jam-edge/1/0"]
        (legend,) = fig.subfigs[0].legends
        assert [t.get_text() for t in legend.get_texts()] == expected
        assert legend.get_title().get_text() == "total backlash c on the line of action"
        colours = [ln.get_color() for ln in data(ax, prefix)]
        assert len(set(colours)) == N_BACKLASH
        assert colours[2] == "#000000"  # the critical gap in black
    assert not lines(figures["stiffness"].axes[0], "marked")
    assert len(lines(figures["natural_frequency"].axes[0], "marked")) == 4


# --- the data ----------------------------------------------------------------------------------
def test_plotted_stiffness_equals_the_model(figures, model, closure, backlash):
    (ax,) = figures["stiffness"].axes
    for i, ln in enumerate(data(ax, "k")):
        t = np.asarray(ln.get_xdata(), dtype=float)
        r = mesh_natural_frequency(model, t, closure.total_m, backlash[i], CHI)
        assert not r.jammed.any()
        np.testing.assert_allclose(ln.get_ydata(), r.k_mean_N_per_m / 1e6, rtol=1e-13,
                                   err_msg=f"k/{i}")


def test_plotted_stiffness_is_the_cycle_mean_of_the_pair_stiffness(figures, model, closure,
                                                                   backlash):
    # independent: seed 000's Eq. (1) at the quadrature nodes (thermoelastic_mesh_stiffness),
    # summed with the weights over the base pitch
    (ax,) = figures["stiffness"].axes
    for i, ln in enumerate(data(ax, "k")):
        t = np.asarray(ln.get_xdata(), dtype=float)[::9]
        r = thermoelastic_mesh_stiffness(PAIR, t, closure.total_m, backlash[i], CHI,
                                         s_m=model.s_m)
        k_mean = (r.k_N_per_m * model.weights).sum(axis=-1)
        # rtol 1e-9: round-off amplified by ~1e5 next to the jam edge (see below)
        np.testing.assert_allclose(np.asarray(ln.get_ydata())[::9], k_mean / 1e6, rtol=1e-9,
                                   err_msg=f"k/{i}")


def test_plotted_frequency_equals_the_model_and_the_scalar_loop(figures, model, closure,
                                                                backlash):
    (ax,) = figures["natural_frequency"].axes
    (ax_k,) = figures["stiffness"].axes
    for i, (ln, ln_k) in enumerate(zip(data(ax, "fn"), data(ax_k, "k"), strict=True)):
        t = np.asarray(ln.get_xdata(), dtype=float)
        np.testing.assert_array_equal(t, ln_k.get_xdata())
        r = mesh_natural_frequency(model, t, closure.total_m, backlash[i], CHI)
        np.testing.assert_allclose(ln.get_ydata(), r.f_n_Hz / 1e3, rtol=1e-13)
        # f_n = sqrt(k / m_e) / 2 pi between the two figures
        k = np.asarray(ln_k.get_ydata()) * 1e6
        np.testing.assert_allclose(ln.get_ydata(),
                                   np.sqrt(k / model.equivalent_mass_kg) / (2e3 * math.pi),
                                   rtol=1e-12)
        for j in (0, t.size // 2, t.size - 1):
            ref = mesh_natural_frequency_scalar(model, t[j], closure.total_m, backlash[i], CHI)
            # rel 1e-9: next to the jam edge Eq. (1)'s denominator is ~1e-5 of its terms, so the
            # two summation orders differ by ~1e5 eps there
            assert ln.get_ydata()[j] == pytest.approx(ref / 1e3, rel=1e-9)


def test_nothing_nan_infinite_or_negative_is_drawn(figures):
    for fig in figures.values():
        (ax,) = fig.axes
        for ln in ax.get_lines():
            x = np.asarray(ln.get_xdata(), dtype=float)
            y = np.asarray(ln.get_ydata(), dtype=float)
            assert np.all(np.isfinite(x)) and np.all(np.isfinite(y)), ln.get_gid()
            assert np.all(x >= 0) and np.all(y >= 0), ln.get_gid()
        for ln in [*lines(ax, "k/").values(), *lines(ax, "fn/").values()]:
            assert np.all(np.asarray(ln.get_ydata()) > 0)


def test_jammed_torques_are_left_out_and_marked(figures, model, c_star, backlash):
    """SEED-NOTES 10: jammed below ``T = r_b1 (c* - c) max(k_EP / R)``, marked, not drawn."""
    for fig, prefix in ((figures["stiffness"], "k"), (figures["natural_frequency"], "fn")):
        (ax,) = fig.axes
        spans = {p.get_gid(): p for p in ax.patches if (p.get_gid() or "").startswith("jammed")}
        assert sorted(spans) == ["jammed/0/0", "jammed/1/0"]
        for i, ln in enumerate(data(ax, prefix)):
            t = np.asarray(ln.get_xdata())
            if backlash[i] < c_star:
                edge = jam_edge(model, c_star, backlash[i])
                assert t.min() > edge and t.min() < edge * (1 + 1e-4)  # drawn from the edge
                span = spans[f"jammed/{i}/0"]
                xy = span.get_patch_transform().transform(span.get_path().vertices)
                assert xy[:, 0].min() == 0.0
                assert xy[:, 0].max() == pytest.approx(edge, rel=1e-9)
                x_edge = lines(ax, f"jam-edge/{i}/0")[f"jam-edge/{i}/0"].get_xdata()
                np.testing.assert_allclose(x_edge, edge, rtol=1e-9)
            else:
                assert t.min() < 5.0  # not jammed: from the lightest torque of the grid
        # the c = 0 line is jammed up to ~201 N m with the hot-state closure
        assert jam_edge(model, c_star, 0.0) == pytest.approx(201.0, abs=0.5)
        texts = [t.get_text().replace("\n", " ") for t in ax.texts if t.get_gid() == "jam-text"]
        assert texts == ["gears jammed by thermal growth (formula not valid)"]
        labels = [t.get_text() for t in ax.texts if (t.get_gid() or "").startswith("jam-label")]
        assert labels[0].startswith("c = 0: jammed below 201 N·m")
        assert labels[1].startswith("c = c*/2: jammed below 100 N·m")


def test_the_critical_gap_line_is_flat_at_the_elastic_stiffness(figures, model):
    """Seed 000 Table 5: at ``c = c*`` the stiffness is that of zero backlash at any load."""
    (ax,) = figures["stiffness"].axes
    line = data(ax, "k")[2]
    y = np.asarray(line.get_ydata())
    np.testing.assert_allclose(y, model.k_EP_mean_N_per_m / 1e6, rtol=1e-13, err_msg=SRC)
    assert np.ptp(y) <= 1e-12 * y[0]
    assert line.get_xdata()[0] < 5.0 and line.get_xdata()[-1] == 500.0  # the whole range
    (label,) = [t.get_text() for t in ax.texts if t.get_gid() == "critical-label"]
    assert label == "c = c*: k̄ = k̄$_{EP}$ = 461.3 N/µm at every torque"
    (ax_f,) = figures["natural_frequency"].axes
    f = np.asarray(data(ax_f, "fn")[2].get_ydata())
    np.testing.assert_allclose(f, model.elastic_natural_frequency_Hz / 1e3, rtol=1e-13)
    (label,) = [t.get_text() for t in ax_f.texts if t.get_gid() == "critical-label"]
    assert label == "c = c*: $f_n$ = 7.93 kHz (elastic) at every torque"


def test_table_5_regimes_read_off_the_figure(figures, backlash, c_star, model):
    """Below c* the stiffness falls with load (towards k_EP), above c* it rises (to k_EP)."""
    (ax,) = figures["stiffness"].axes
    k_ep = model.k_EP_mean_N_per_m / 1e6
    for i, ln in enumerate(data(ax, "k")):
        y = np.asarray(ln.get_ydata())
        if backlash[i] < c_star:
            assert np.all(np.diff(y) < 0) and np.all(y > k_ep), f"{SRC} Table 5, row {i}"
        elif backlash[i] > c_star:
            assert np.all(np.diff(y) > 0) and np.all(y < k_ep), f"{SRC} Table 5, row {i}"
    # at every torque the stiffness falls as the backlash grows (seed 000 conclusion 2)
    valid_rows = [np.asarray(ln.get_ydata())[-1] for ln in data(ax, "k")]
    assert np.all(np.diff(valid_rows) < 0)
    # the axis reaches 2.2 k_EP; the c < c* lines leave it at the top near their jam edge
    assert ax.get_ylim()[1] == pytest.approx(2.2 * k_ep, rel=1e-12)


def test_table_6_torques_are_marked(figures):
    (ax,) = figures["natural_frequency"].axes
    marks = [lines(ax, f"marked/{j}")[f"marked/{j}"] for j in range(4)]
    np.testing.assert_array_equal([m.get_xdata()[0] for m in marks], TABLE_6_TORQUES_NM)
    assert all(m.get_xdata()[0] == m.get_xdata()[1] for m in marks)  # vertical
    (top,) = ax.child_axes
    np.testing.assert_array_equal(top.get_xticks(), TABLE_6_TORQUES_NM)
    assert [t.get_text() for t in top.get_xticklabels()] == ["3.3", "35.3", "183.4", "302"]


# --- the plotting functions on their own -------------------------------------------------------
@pytest.fixture(scope="module")
def small(model, closure, c_star):
    torque = np.linspace(5.0, 400.0, 40)
    c = np.array([0.0, c_star, 40e-6])
    r = mesh_natural_frequency(model, torque, closure.total_m, c[:, None], CHI)
    return torque, c, r


def test_per_face_width_units_and_custom_labels(small, c_star):
    torque, c, r = small
    fig = plot_stiffness_vs_load(torque, r, c, c_star, face_width_m=PAIR.face_width_m,
                                 labels=["none", "critical", "worn"],
                                 colors=["red", "black", "blue"])
    (ax,) = fig.axes
    assert ax.get_ylabel() == "mean mesh stiffness k̄ per face width (N/(mm·µm))"
    (legend,) = fig.subfigs[0].legends
    assert [t.get_text() for t in legend.get_texts()][:3] == ["none", "critical", "worn"]
    for i, ln in enumerate(data(ax, "k")):
        ok = ~r.jammed[i]
        np.testing.assert_array_equal(ln.get_xdata(), torque[ok])
        np.testing.assert_allclose(ln.get_ydata(),
                                   r.k_mean_N_per_m[i][ok] / PAIR.face_width_m / 1e9,
                                   rtol=1e-13)
    assert len(fig.subfigs) == 2  # no note given: header and axes only


def test_double_flank_results_are_masked_the_same(model, closure, c_star):
    # the double-flank stand-in is a separate model (thermoelastic module notes): not drawn
    torque = np.linspace(5.0, 400.0, 40)
    r = mesh_natural_frequency(model, torque, closure.total_m, 0.0, CHI,
                               jammed_model="double_flank")
    r2 = mesh_natural_frequency(model, torque, closure.total_m, np.array([[0.0]]), CHI,
                                jammed_model="double_flank")
    assert r.jammed.any() and np.all(np.isfinite(r.f_n_Hz))
    fig = plot_natural_frequency_vs_load(torque, r2, [0.0], c_star, marked_torques_Nm=())
    (ax,) = fig.axes
    (ln,) = data(ax, "fn")
    np.testing.assert_array_equal(ln.get_xdata(), torque[~r.jammed])
    assert not ax.child_axes


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"torque_Nm": [5.0]}, r"`torque_Nm` must be 1-D with at least 2 torques"),
    ({"torque_Nm": np.linspace(400.0, 5.0, 40)}, r"`torque_Nm` must be finite, > 0 and incr"),
    ({"backlash_m": [0.0, 1e-5]}, r"`result` must have shape \(len\(backlash_m\), len\(torq"),
    ({"backlash_m": [0.0, -1e-6, 4e-5]}, r"`backlash_m` must be 1-D, finite and >= 0"),
    ({"result": np.zeros((3, 40))}, r"`result` must be a NaturalFrequency"),
    ({"critical_gap_m": math.nan}, r"`critical_gap_m` must be finite"),
    ({"face_width_m": 0.0}, r"`face_width_m` must be finite and > 0, was 0.0"),
    ({"labels": ["a"]}, r"`labels` must give one label per backlash \(3\)"),
    ({"colors": ["red", "blue", "nocolour"]}, r"`colors` must hold matplotlib colours"),
    ({"y_max": -1.0}, r"`y_max` must be finite and > 0, was -1.0"),
])
def test_invalid_arguments_are_refused(small, c_star, kwargs, match):
    torque, c, r = small
    args = {"torque_Nm": torque, "result": r, "backlash_m": c, "critical_gap_m": c_star,
            **kwargs}
    with pytest.raises(ValueError, match=match):
        plot_stiffness_vs_load(args.pop("torque_Nm"), args.pop("result"),
                               args.pop("backlash_m"), args.pop("critical_gap_m"), **args)


def test_thermal_figures_refuses_a_bad_closure():
    with pytest.raises(ValueError, match="`thermal_closure` must be a ThermalClosure"):
        thermal_figures(thermal_closure=10e-6)  # type: ignore[arg-type]


def test_a_given_closure_without_jam_draws_every_torque():
    # no closure: c* = 0, nothing jammed, c = 0 flat at k_EP (seed 000 Table 4, c = 0)
    figs = thermal_figures(backlash_m=[0.0, 40e-6], n_torques=40,
                           thermal_closure=ThermalClosure(0.0, "no thermal closure (cold)"))
    (ax,) = figs["stiffness"].axes
    assert not [p for p in ax.patches if (p.get_gid() or "").startswith("jammed")]
    assert not [t for t in ax.texts if t.get_gid() == "jam-text"]
    flat, rising = data(ax, "k")
    assert np.ptp(flat.get_ydata()) == 0.0 and np.all(np.diff(rising.get_ydata()) > 0)
    (legend,) = figs["stiffness"].subfigs[0].legends
    assert [t.get_text() for t in legend.get_texts()] == ["c = c* = 0 µm", "c = 40 µm"]


# --- files -------------------------------------------------------------------------------------
def test_save_png_writes_a_valid_png(small, c_star, tmp_path):
    torque, c, r = small
    fig = plot_natural_frequency_vs_load(torque, r, c, c_star, note="a note")
    dpi = 40
    path = save_png(fig, tmp_path / "sub" / "thermal_fn.png", dpi=dpi)
    assert path == tmp_path / "sub" / "thermal_fn.png"
    data_ = path.read_bytes()
    assert data_[:8] == b"\x89PNG\r\n\x1a\n"
    length, kind = struct.unpack(">I4s", data_[8:16])
    assert (length, kind) == (13, b"IHDR")
    width, height = struct.unpack(">II", data_[16:24])
    (crc,) = struct.unpack(">I", data_[24 + 5:24 + 9])
    assert crc == zlib.crc32(data_[12:16 + 13])
    w_in, h_in = fig.get_size_inches()
    assert (width, height) == (round(w_in * dpi), round(h_in * dpi))
    assert data_[-12:] == b"\x00\x00\x00\x00IEND\xaeB`\x82"


def test_no_pyplot_and_no_global_state():
    # STYLE.md 5 and 15: figures without pyplot's global state, no import-time side effects
    code = (
        "import sys, matplotlib\n"
        "def rc():  # reading rcParams['backend'] would itself import pyplot\n"
        "    return {k: matplotlib.rcParams[k] for k in matplotlib.rcParams if k != 'backend'}\n"
        "before = rc()\n"
        "import rigtools.plots.thermal\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
        "from rigtools.plots import thermal_figures\n"
        "figs = thermal_figures(n_torques=20)\n"
        "for f in figs.values():\n"
        "    f.canvas.draw()\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
        "assert rc() == before\n"
        "print(sorted(figs))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "['natural_frequency', 'stiffness']"


def test_line2d_is_the_only_data_artist(figures):
    # every data line is a Line2D on the one data axes (read back above); no collections
    for fig in figures.values():
        (ax,) = fig.axes
        assert not ax.collections
        assert all(isinstance(ln, Line2D) for ln in ax.get_lines())
