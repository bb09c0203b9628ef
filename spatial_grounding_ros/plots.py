# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""PNG figures: the entity map, the value map and the relation map |Z1| side by side."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .entities import EntityTable  # noqa: E402


def plot_grounding(
    path: str | Path,
    grid: np.ndarray,
    entities: EntityTable,
    values: np.ndarray,
    relation_map: np.ndarray,
    title: str,
    goal=None,
    true_goal=None,
    path_cells=None,
) -> Path:
    """
    Three panels.

    Map (entity names as letters), predicted values, |Z1|; marks the predicted goal (x), the true
    goal (o) and an agent path if given.
    """
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2))
    h, w = grid.shape
    axes[0].imshow(np.isin(grid, entities.obstacles), cmap='Blues', vmin=0, vmax=2)
    for (r, c), e in np.ndenumerate(grid):
        if e and e not in entities.obstacles:
            name = entities.names[e]
            axes[0].text(c, r, name.split('_')[-1][:3], ha='center', va='center', fontsize=7)
    panels = [
        (axes[1], values, 'value map', 'viridis'),
        (axes[2], np.abs(relation_map), 'relation map |Z1|', 'magma'),
    ]
    for ax, img, label, cmap in panels:
        im = ax.imshow(img, cmap=cmap)
        ax.set_title(label)
        fig.colorbar(im, ax=ax, fraction=0.046)
    axes[0].set_title('map')
    for ax in axes:
        if path_cells is not None and len(path_cells) > 1:
            pc = np.asarray(path_cells)
            ax.plot(pc[:, 1], pc[:, 0], '-', color='orange', lw=2)
        if true_goal is not None:
            ax.plot(true_goal[1], true_goal[0], 'o', mfc='none', mec='lime', ms=14, mew=2)
        if goal is not None:
            ax.plot(goal[1], goal[0], 'x', color='red', ms=12, mew=3)
        ax.set_xticks(range(w))
        ax.set_yticks(range(h))
        ax.tick_params(labelsize=6)
    fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
