"""Fig. 3e says which end its lateral panel measures and how many trials each mean has (a
review: the batch's figure showed the trailing end's excursions as 'lateral' and no counts)."""

import matplotlib

matplotlib.use("Agg")

from flutterswim.fitting import read_trials, summarise, plot_trials  # noqa: E402

ROWS = """voltage_V,sample,period_s,advance_mm,lateral_mm
70,a,0.41,0.30,0.95
70,b,0.43,0.28,0.90
70,c,0.40,0.33,1.00
85,a,0.37,0.40,1.12
85,b,0.38,0.38,1.10
"""


def test_the_lateral_end_and_the_trial_counts_are_on_the_figure(tmp_path):
    import matplotlib.pyplot as plt

    (tmp_path / "t.csv").write_text(ROWS)
    trials = read_trials(tmp_path / "t.csv")
    sm = summarise(trials)
    for tip in ("trailing", "leading"):
        fig = plot_trials(sm, None, trials=trials, tip=tip)
        axs = fig.axes
        assert f"{tip} end" in axs[2].get_ylabel()
        counts = sorted(t.get_text() for t in axs[0].texts)
        assert counts == sorted(f"n={int(n)}" for n in sm.n) == ["n=2", "n=3"]
        # every trial and mean stays inside the panel with its count below them
        lo, hi = axs[0].get_ylim()
        assert lo < min(trials.values[:, 0]) and hi > max(trials.values[:, 0])
        plt.close(fig)
