"""Figures of the mesh cycle (rigtools.plots.stiffness): structure, data read back, PNG files.

The figures are checked as objects: panels, axis labels with units, legends, the number of
lines, and the data of every line read back from its ``Line2D`` against the ``MeshCycle``
arrays it was drawn from (seed 003 Figs. 4 and 6 are the model of the layout). The physics
identities that must survive plotting (VVMS = FVMS at T = 0, seed 003 Sec. 2.6; no corner
contact at Delta = 1, Sec. 5.1) are read off the figures too.
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
from models.stiffness import (
    mesh_cycle,
    normalised_tip_relief,
    pair_compliance,
    prepare_mesh_cycle,
    tabulate_compliance,
)
from rigtools.plots import FIGURE_WIDTH_IN, mesh_cycle_figures, plot_mesh_cycle, save_png

PAIR = load_gear_set("kahraman-blankenship").pair
B = PAIR.face_width_m
TORQUES = (0.0, 100.0, 200.0, 340.0)
RELIEFS = (0.0, 0.5, 1.0)
DESIGN_TORQUE_NM = 340.0
N_PHASES = 96
N_PER_MM_UM = 1e9


@pytest.fixture(scope="module")
def compliance():
    return tabulate_compliance(PAIR, lambda s: pair_compliance(PAIR, s).total_m_per_N)


@pytest.fixture(scope="module")
def torque_cycles(compliance):
    geo = prepare_mesh_cycle(PAIR, compliance, n_phases=N_PHASES)
    return [geo.solve(t) for t in TORQUES]


@pytest.fixture(scope="module")
def torque_fig(torque_cycles):
    fig = plot_mesh_cycle(torque_cycles, [f"{t:g} N·m" for t in TORQUES],
                          legend_title="pinion torque", face_width_m=B)
    fig.canvas.draw()  # tick labels and layout are final only after a draw
    return fig


@pytest.fixture(scope="module")
def figures():
    return mesh_cycle_figures(torques_Nm=TORQUES, reliefs=RELIEFS,
                              relief_torque_Nm=DESIGN_TORQUE_NM, n_phases=N_PHASES)


def lines(ax, prefix):
    """Data lines of an axes whose gid starts with ``prefix``, by gid."""
    return {ln.get_gid(): ln for ln in ax.get_lines()
            if (ln.get_gid() or "").startswith(prefix)}


def header_legend(fig):
    (legend,) = fig.subfigs[0].legends
    return legend


# --- structure --------------------------------------------------------------------------------
def test_three_panels_share_the_phase_axis(torque_fig):
    assert isinstance(torque_fig, Figure)
    assert torque_fig.get_size_inches()[0] == pytest.approx(FIGURE_WIDTH_IN)
    ax_k, ax_lsr, ax_x = torque_fig.axes
    for ax in (ax_lsr, ax_x):
        assert ax.get_shared_x_axes().joined(ax_k, ax)
        assert ax.get_xlim() == (0.0, 1.0)
    assert torque_fig.subfigs[0].get_suptitle()


def test_every_axis_names_its_quantity_and_unit(torque_fig):
    ax_k, ax_lsr, ax_x = torque_fig.axes
    assert "VVMS" in ax_k.get_ylabel() and "FVMS" in ax_k.get_ylabel()
    assert "per face width (N/(mm·µm))" in ax_k.get_ylabel()
    assert "load-sharing ratio" in ax_lsr.get_ylabel() and "(–)" in ax_lsr.get_ylabel()
    assert ax_x.get_ylabel() == "LSTE $x$ (µm)"
    assert ax_x.get_xlabel().startswith("mesh-cycle phase τ")
    (top,) = ax_k.child_axes  # the contact point of pair #2 at the zone boundaries
    assert [t.get_text() for t in top.get_xticklabels()] == ["A", "LPSTC", "HPSTC"]


def test_line_counts_per_panel(torque_fig, torque_cycles):
    ax_k, ax_lsr, ax_x = torque_fig.axes
    assert sorted(lines(ax_k, "vvms")) == [f"vvms/{i}" for i in range(4)]
    assert list(lines(ax_k, "fvms")) == ["fvms"]  # one FVMS: load-independent (Sec. 2.4)
    assert len(lines(ax_x, "lste")) == 4
    # load sharing: pairs #1 and #2 at T = 0, and the incoming pair #3 too once corner
    # contact sets in (seed 003 Fig. 4: triple contact under load)
    lsr = lines(ax_lsr, "lsr")
    assert sorted(lsr) == sorted(["lsr/0/1", "lsr/0/0"]
                                 + [f"lsr/{i}/{m}" for i in (1, 2, 3) for m in (1, 0, -1)])
    loaded = sum(int(np.any(c.load_sharing_ratio[:, k] > 0))
                 for c in torque_cycles for k in range(c.slot_offset.size))
    assert len(lsr) == loaded == 11


def test_legends_say_what_each_line_is(torque_fig):
    ax_k, ax_lsr, _ = torque_fig.axes
    legend = header_legend(torque_fig)
    assert legend.get_title().get_text() == "pinion torque"
    texts = [t.get_text() for t in legend.get_texts()]
    assert texts == ["0 N·m", "100 N·m", "200 N·m", "340 N·m", "FVMS (all cases)"]
    # the legend's colours are the cases' colours in every panel, all distinct
    colours = [h.get_color() for h in legend.legend_handles[:4]]
    assert len(set(colours)) == 4
    for i, colour in enumerate(colours):
        assert lines(ax_k, f"vvms/{i}")[f"vvms/{i}"].get_color() == colour
        for ln in lines(ax_lsr, f"lsr/{i}/").values():
            assert ln.get_color() == colour
    # one line style per pair, named in the load-sharing panel's legend
    pair_legend = ax_lsr.get_legend()
    names = [t.get_text() for t in pair_legend.get_texts()]
    assert names == ["pair #1 (outgoing)", "pair #2 (middle)", "pair #3 (incoming)"]
    styles = [h.get_linestyle() for h in pair_legend.legend_handles]
    assert len(set(styles)) == 3
    for m, style in zip((1, 0, -1), styles, strict=True):
        for ln in lines(ax_lsr, "lsr").values():
            if ln.get_gid().endswith(f"/{m}"):
                assert ln.get_linestyle() == style


def test_contact_zones_are_shaded_from_the_geometry(torque_fig):
    # seed 003 Fig. 4: pair #2 at LPSTC to pair #2 at HPSTC is the theoretical single zone
    A, pb = PAIR.start_of_contact, PAIR.base_pitch
    lo = (PAIR.lowest_point_single_contact - A) / pb
    hi = (PAIR.highest_point_single_contact - A) / pb
    for ax in torque_fig.axes:
        (zone,) = [p for p in ax.patches if p.get_gid() == "zone"]
        xy = zone.get_patch_transform().transform(zone.get_path().vertices)
        assert xy[:, 0].min() == pytest.approx(lo, abs=1e-12)
        assert xy[:, 0].max() == pytest.approx(hi, abs=1e-12)
    names = [t.get_text() for t in torque_fig.axes[0].texts]
    assert "double contact\n(theoretical)" in names and "single contact\n(theoretical)" in names


# --- the data ---------------------------------------------------------------------------------
def test_plotted_data_equal_the_mesh_cycle_arrays(torque_fig, torque_cycles):
    ax_k, ax_lsr, ax_x = torque_fig.axes
    for i, c in enumerate(torque_cycles):
        for ax, gid, expected in ((ax_k, f"vvms/{i}", c.vvms_N_m / B / N_PER_MM_UM),
                                  (ax_k, "fvms", c.fvms_N_m / B / N_PER_MM_UM),
                                  (ax_x, f"lste/{i}", c.lste_m * 1e6)):
            ln = lines(ax, gid)[gid]
            np.testing.assert_array_equal(ln.get_xdata(), c.phase)
            np.testing.assert_allclose(ln.get_ydata(), expected, rtol=1e-12, atol=0, err_msg=gid)
        drawn = lines(ax_lsr, f"lsr/{i}/")
        for k, m in enumerate(c.slot_offset):
            gid = f"lsr/{i}/{m}"
            lsr = c.load_sharing_ratio[:, k]
            if gid not in drawn:  # only pairs that never carry load are left out
                assert np.all(lsr == 0), gid
                continue
            y = np.asarray(drawn[gid].get_ydata(), dtype=float)
            np.testing.assert_array_equal(drawn[gid].get_xdata(), c.phase)
            shown = np.isfinite(y)
            np.testing.assert_allclose(y[shown], lsr[shown], rtol=1e-12, atol=0, err_msg=gid)
            assert np.all(lsr[~shown] == 0), gid  # gaps only where the pair is unloaded
            assert np.all(shown[lsr > 0]), gid  # every loaded phase is drawn


def test_zero_torque_vvms_is_drawn_on_the_fvms(torque_fig):
    # seed 003 Sec. 2.6: "In this case (T = 0 and e = 0), the FVMS is same with VVMS"; under load
    # corner contact stiffens the theoretical single zone
    ax_k = torque_fig.axes[0]
    fvms = lines(ax_k, "fvms")["fvms"].get_ydata()
    np.testing.assert_allclose(lines(ax_k, "vvms/0")["vvms/0"].get_ydata(), fvms, rtol=1e-12)
    assert np.all(lines(ax_k, "vvms/3")["vvms/3"].get_ydata() >= fvms * (1 - 1e-9))
    notes = [t.get_text() for t in ax_k.texts if t.get_gid() == "note"]
    assert notes == ["every case here: VVMS = FVMS"]


def test_whole_face_stiffness_without_a_face_width(torque_cycles):
    fig = plot_mesh_cycle(torque_cycles[-1:], ["340 N·m"])
    ax_k = fig.axes[0]
    assert "whole face (N/µm)" in ax_k.get_ylabel()
    np.testing.assert_allclose(lines(ax_k, "vvms/0")["vvms/0"].get_ydata(),
                               torque_cycles[-1].vvms_N_m / 1e6, rtol=1e-12)


def test_one_fvms_per_case_when_the_cases_differ_in_compliance():
    cycles = [mesh_cycle(PAIR, lambda s, c=c: np.full(np.shape(s), c), 100.0, n_phases=32)
              for c in (3e-9, 4e-9)]
    fig = plot_mesh_cycle(cycles, ["stiff", "soft"], colors=["red", "blue"])
    ax_k = fig.axes[0]
    fvms = lines(ax_k, "fvms")
    assert sorted(fvms) == ["fvms/0", "fvms/1"]
    assert [fvms[f"fvms/{i}"].get_color() for i in (0, 1)] == ["red", "blue"]
    np.testing.assert_allclose(fvms["fvms/1"].get_ydata(), cycles[1].fvms_N_m / 1e6, rtol=1e-12)
    texts = [t.get_text() for t in header_legend(fig).get_texts()]
    assert texts == ["stiff", "soft", "FVMS (dashed, colour of its case)"]


# --- the two figures of the report ------------------------------------------------------------
def test_mesh_cycle_figures_torque_and_relief(figures):
    assert set(figures) == {"torque", "relief"}
    torque, relief = figures["torque"], figures["relief"]
    assert all(isinstance(f, Figure) and len(f.axes) == 3 for f in figures.values())
    assert len(lines(torque.axes[0], "vvms")) == 4 and len(lines(relief.axes[0], "vvms")) == 3
    texts = [t.get_text() for t in header_legend(relief).get_texts()]
    assert texts[0] == "Δ = 0 (none)" and texts[1].startswith("Δ = 0.5 (")
    assert texts[2].startswith("Δ = 1 (") and texts[2].endswith(" µm)")
    # the same case (340 N m, no relief) has the same colour and the same data in both figures
    k340 = lines(torque.axes[0], "vvms/3")["vvms/3"]
    k0 = lines(relief.axes[0], "vvms/0")["vvms/0"]
    assert k340.get_color() == k0.get_color()
    np.testing.assert_array_equal(k340.get_ydata(), k0.get_ydata())
    # seed 003 Sec. 5.1: Delta = 1 removes corner contact at 340 N m, so no incoming pair is
    # drawn for it, while without relief the incoming pair takes load early
    lsr = lines(relief.axes[1], "lsr")
    assert "lsr/0/-1" in lsr and "lsr/2/-1" not in lsr


def test_relief_figure_data_match_a_direct_computation(figures, compliance):
    relief = normalised_tip_relief(PAIR, compliance, DESIGN_TORQUE_NM, 0.5)
    c = mesh_cycle(PAIR, compliance, DESIGN_TORQUE_NM, error=relief, n_phases=N_PHASES)
    ax_k, _, ax_x = figures["relief"].axes
    np.testing.assert_allclose(lines(ax_k, "vvms/1")["vvms/1"].get_ydata(),
                               c.vvms_N_m / B / N_PER_MM_UM, rtol=1e-9)
    np.testing.assert_allclose(lines(ax_x, "lste/1")["lste/1"].get_ydata(), c.lste_m * 1e6,
                               rtol=1e-9)


# --- files ------------------------------------------------------------------------------------
def test_save_png_writes_a_valid_png(torque_cycles, tmp_path):
    fig = plot_mesh_cycle(torque_cycles[:2], ["0 N·m", "100 N·m"], face_width_m=B)
    dpi = 40
    path = save_png(fig, tmp_path / "sub" / "cycle.png", dpi=dpi)
    assert path == tmp_path / "sub" / "cycle.png"
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    length, kind = struct.unpack(">I4s", data[8:16])
    assert (length, kind) == (13, b"IHDR")
    width, height = struct.unpack(">II", data[16:24])
    (crc,) = struct.unpack(">I", data[24 + 5:24 + 9])
    assert crc == zlib.crc32(data[12:16 + 13])
    w_in, h_in = fig.get_size_inches()
    assert (width, height) == (round(w_in * dpi), round(h_in * dpi))
    assert data[-12:] == b"\x00\x00\x00\x00IEND\xaeB`\x82"


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"cycles": [], "labels": []}, "`cycles` must hold at least one MeshCycle"),
    ({"labels": ["a"]}, r"`labels` must give one label per cycle \(2\), gave 1"),
    ({"labels": "ab"}, "`labels` must be a sequence of strings"),
    ({"face_width_m": 0.0}, "`face_width_m` must be finite and > 0 m, was 0.0"),
    ({"colors": ["red"]}, r"`colors` must give one colour per cycle \(2\)"),
    ({"colors": ["red", "nocolour"]}, "`colors` must hold matplotlib colours, had 'nocolour'"),
])
def test_invalid_arguments_are_refused(torque_cycles, kwargs, match):
    args = {"cycles": torque_cycles[:2], "labels": ["a", "b"], **kwargs}
    cycles, labels = args.pop("cycles"), args.pop("labels")
    with pytest.raises(ValueError, match=match):
        plot_mesh_cycle(cycles, labels, **args)


def test_cycles_on_different_phase_grids_are_refused(torque_cycles):
    other = mesh_cycle(PAIR, lambda s: np.full(np.shape(s), 3e-9), 0.0, n_phases=32)
    with pytest.raises(ValueError, match=r"`cycles\[1\]` must share the phase grid"):
        plot_mesh_cycle([torque_cycles[0], other], ["a", "b"])
    with pytest.raises(ValueError, match="`fig` must be a matplotlib Figure"):
        save_png(Line2D([], []), "never.png")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="`dpi` must be finite and > 0"):
        save_png(Figure(), "never.png", dpi=math.nan)


def test_no_pyplot_and_no_global_state():
    # STYLE.md 5 and 15: figures without pyplot's global state, no import-time side effects
    code = (
        "import sys, matplotlib\n"
        "def rc():  # reading rcParams['backend'] would itself import pyplot\n"
        "    return {k: matplotlib.rcParams[k] for k in matplotlib.rcParams if k != 'backend'}\n"
        "before = rc()\n"
        "import rigtools.plots\n"
        "from rigtools.plots import mesh_cycle_figures\n"
        "figs = mesh_cycle_figures(torques_Nm=(0.0, 340.0), reliefs=(1.0,), n_phases=32)\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
        "assert rc() == before\n"
        "print(sorted(figs))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "['relief', 'torque']"
