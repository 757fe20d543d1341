import numpy as np

from eqrec.studies.pipeline.outputs import save_figure
from eqrec.studies.plotting import guarantee_bars, paper_style, trajectory_panel


def test_trajectory_panel_writes_pdf_and_png(tmp_path):
    import matplotlib.pyplot as plt

    paper_style()
    fig, axes = plt.subplots(3, 1)
    errs = np.random.default_rng(0).uniform(-1, 1, (5, 7, 3))
    trajectory_panel(axes, errs, [1] + [1.2] * 5 + [1], "test")
    assert len(axes[0].patches) == 7  # one guarantee bar per time step
    assert axes[-1].get_xlabel() == "time step $t$"
    save_figure(fig, tmp_path / "f.pdf", tmp_path / "f.png")
    assert (tmp_path / "f.pdf").stat().st_size > 1000 and (tmp_path / "f.png").stat().st_size > 1000


def test_guarantee_bar_heights():
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    guarantee_bars(ax, [1.0, 2.0])
    assert [p.get_height() for p in ax.patches] == [2.0, 4.0]
    plt.close(fig)


def test_figures_are_byte_reproducible(tmp_path):
    import matplotlib.pyplot as plt

    for name in ("a", "b"):
        fig, ax = plt.subplots()
        ax.plot([0, 1], [1, 0])
        save_figure(fig, tmp_path / f"{name}.pdf")
    assert (tmp_path / "a.pdf").read_bytes() == (tmp_path / "b.pdf").read_bytes()
