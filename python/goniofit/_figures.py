"""The report's pictures as matplotlib figures (``FitResult.figures("matplotlib")``)."""

from __future__ import annotations

import io
from typing import Any, Dict


def to_matplotlib(pngs: Dict[str, bytes]) -> Dict[str, Any]:
    """One matplotlib figure per picture, showing the picture at its own pixel size
    (100 dpi) without axes. Needs matplotlib (``pip install 'goniofit[plot]'``)."""
    try:
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt
    except ImportError as e:
        raise ImportError(
            'figures("matplotlib") needs matplotlib: pip install matplotlib '
            '(or figures("svg") / figures("png"), which need nothing else)'
        ) from e
    figures = {}
    for name, png in pngs.items():
        image = mpimg.imread(io.BytesIO(png), format="png")
        height, width = image.shape[:2]
        fig = plt.figure(figsize=(width / 100, height / 100), dpi=100)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.imshow(image)
        ax.set_axis_off()
        figures[name] = fig
    return figures
