"""``budget.png`` reads: every bar's label lies inside its axis, clear of the other labels and of
the effects' names (checked on the committed Unreal study's budget, whose shares run from -115 %
to +102 %, with the figure's own text extents from matplotlib's renderer)."""

import json
from pathlib import Path

from fogref.study.budget.report import budget_figure

BUDGET = Path(__file__).resolve().parents[1] / "reports" / "unreal_study" / "budget.json"


def test_no_label_of_the_budget_figure_overlaps_another_or_leaves_its_axis():
    fig = budget_figure(json.loads(BUDGET.read_text()))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    names = [t.get_window_extent(renderer) for t in fig.axes[0].get_yticklabels() if t.get_text()]
    labels = []
    for ax in fig.axes:
        box = ax.get_window_extent(renderer)
        for t in ax.texts:
            b = t.get_window_extent(renderer)
            assert box.x0 <= b.x0 and b.x1 <= box.x1, f"label {t.get_text()!r} leaves its axis"
            labels.append((t.get_text(), b))
    assert len(labels) == 18  # 9 Shapley shares and 9 chain shares
    for i, (text, b) in enumerate(labels):
        assert not any(b.overlaps(n) for n in names), f"label {text!r} covers an effect's name"
        for other, c in labels[i + 1 :]:
            assert not b.overlaps(c), f"labels {text!r} and {other!r} overlap"
