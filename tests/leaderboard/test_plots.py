"""The report's bar chart: every value label is dark text on white, outside its bar, and inside the axes."""

from __future__ import annotations

import lb_fixtures
import matplotlib.pyplot as plt
import numpy as np
from matplotlib import colors as mcolors

from main_bench.leaderboard.plots import bars_panel
from main_bench.leaderboard.submissions import load_submission
from main_bench.leaderboard.tables import TableSettings, build_tables

episodes_dir = lb_fixtures.episodes_dir
three_results = lb_fixtures.three_results


def luminance(color) -> float:
    r, g, b = mcolors.to_rgb(color)
    return 0.2126 * r + 0.7152 * g + 0.0722 * b


def test_value_labels_are_dark_outside_short_and_long_bars(three_results):
    tracks, _ = build_tables([load_submission(r) for r in three_results], TableSettings(n_resamples=100))
    short = long = 0
    for table in tracks:
        fig, ax = plt.subplots()
        labels = bars_panel(ax, table)
        fig.canvas.draw()
        render = fig.canvas.get_renderer()
        bars = [p for p in ax.patches if p.get_width() >= 0 and p.get_height() > 0.3]
        assert len(labels) == len(bars) == 2 * len(table.entries)
        for text, bar in zip(labels, bars, strict=True):
            assert luminance(text.get_color()) < 0.25 and luminance(text.get_bbox_patch().get_facecolor()) > 0.9
            end = bar.get_x() + bar.get_width()
            box = text.get_window_extent(render).transformed(ax.transData.inverted())
            assert box.x0 >= end - 1e-9, (text.get_text(), end)  # right of the bar, never on its colour
            assert box.x1 <= ax.get_xlim()[1]  # and inside the panel
            assert float(text.get_text()) == np.round(bar.get_width(), 3)
            short += bar.get_width() < 0.1
            long += bar.get_width() > 0.8
        plt.close(fig)
    assert short and long  # both kinds were checked
