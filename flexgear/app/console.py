"""Console output shared by the CLI and the study scripts: Markdown tables and progress bars."""
from __future__ import annotations

import sys


def markdown_table(rows, headers) -> str:
    """A Markdown table (pipes, padded columns) of ``rows`` under ``headers``."""
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(headers)]
    line = "| " + " | ".join(str(h).ljust(w) for h, w in zip(headers, widths)) + " |"
    sep = "|" + "|".join("-" * (w + 2) for w in widths) + "|"
    body = ["| " + " | ".join(str(c).ljust(w) for c, w in zip(r, widths)) + " |" for r in rows]
    return "\n".join([line, sep, *body])


def progress_bar(total_s: float):
    """A tqdm bar over ``total_s`` simulated seconds; returns (bar, update(fraction))."""
    from tqdm import tqdm

    bar = tqdm(total=round(total_s, 4), unit="s sim", bar_format="{l_bar}{bar}| {n:.3f}/{total:.3f} s simulated "
               "[{elapsed}<{remaining}]", file=sys.stderr, disable=None)

    def update(frac):
        bar.n = round(frac * total_s, 4)
        bar.refresh()

    return bar, update
