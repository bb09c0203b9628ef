# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
PNG figures.

The entity map, the value map and the relation map |Z1| side by side (plot_grounding); the
robustness curves (plot_robustness); a model's explanation of one grounding, with its
attention over words (plot_explanation).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..core.entities import EntityTable  # noqa: E402


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

    Map (entity names as letters), predicted values, |Z1| (said to be none when all zero: no
    network ran); marks the predicted goal (x), the true goal (o) and an agent path if given.
    """
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2))
    draw_map(axes[0], grid, entities)
    draw_heat_maps(
        fig,
        [
            (axes[1], values, 'value map', 'viridis'),
            (axes[2], np.abs(relation_map), relation_title(relation_map), 'magma'),
        ],
    )
    for ax in axes:
        if path_cells is not None and len(path_cells) > 1:
            pc = np.asarray(path_cells)
            ax.plot(pc[:, 1], pc[:, 0], '-', color='orange', lw=2)
        mark_goals(ax, goal, true_goal, grid.shape)
    fig.suptitle(title)
    return save(fig, path)


def relation_title(relation_map: np.ndarray) -> str:
    """
    Title the |Z1| panel: a network's is never all zero, so an all-zero one says none ran.

    The grammar placed the goal itself, or the grounding declined before the network.
    """
    if np.any(relation_map):
        return 'relation map |Z1|'
    return 'relation map |Z1|: none\n(no network ran)'


def draw_map(ax, grid: np.ndarray, entities: EntityTable) -> None:
    """
    Draw the entity map: obstacles shaded, objects as the first letters of their names.

    Kinds past the table (the robustness study's unseen objects, data/noise.py) are blue stars in a
    circle, as in the paper's figures.
    """
    ax.imshow(np.isin(grid, entities.obstacles), cmap='Blues', vmin=0, vmax=2)
    for (r, c), e in np.ndenumerate(grid):
        if e >= len(entities):
            ax.plot(c, r, '*', color='royalblue', ms=10)
            ax.plot(c, r, 'o', mfc='none', mec='royalblue', ms=14)
        elif e and e not in entities.obstacles:
            name = entities.names[e]
            ax.text(c, r, name.split('_')[-1][:3], ha='center', va='center', fontsize=7)
    ax.set_title('map')


def draw_heat_maps(fig, panels) -> None:
    """Draw (axis, map, title, colour map) panels, each with a colour bar."""
    for ax, img, label, cmap in panels:
        im = ax.imshow(img, cmap=cmap)
        ax.set_title(label)
        fig.colorbar(im, ax=ax, fraction=0.046)


def mark_goals(ax, goal, true_goal, shape) -> None:
    """Mark the predicted goal (red x) and the true one (green o); ticks on every cell."""
    if true_goal is not None:
        ax.plot(true_goal[1], true_goal[0], 'o', mfc='none', mec='lime', ms=14, mew=2)
    if goal is not None:
        ax.plot(goal[1], goal[0], 'x', color='red', ms=12, mew=3)
    ax.set_xticks(range(shape[1]))
    ax.set_yticks(range(shape[0]))
    ax.tick_params(labelsize=6)


def save(fig, path: str | Path, dpi: int = 80) -> Path:
    """Write a figure to a PNG (making its folder) and close it."""
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_robustness(rows: list[dict], path: str | Path) -> Path:
    """
    Plot the paper's robustness curves: MD's relative change against k.

    One panel per task (rows) and noise (columns), one line per checkpoint, named by its model
    (by its checkpoint, when a panel has two of one model: then every line is, so none reads
    as a family of its own); `rows` as robustness.study returns them.
    """
    tasks = list(dict.fromkeys(r['task'] for r in rows))
    noises = list(dict.fromkeys(r['noise'] for r in rows))
    fig, axes = plt.subplots(
        len(tasks), len(noises), figsize=(4 * len(noises), 3 * len(tasks)), squeeze=False,
        sharex=True,
    )
    for (t, task), (n, noise) in ((t, n) for t in enumerate(tasks) for n in enumerate(noises)):
        ax = axes[t][n]
        lines = [r for r in rows if r['task'] == task and r['noise'] == noise]
        checkpoints = list(dict.fromkeys(r['checkpoint'] for r in lines))
        models = [next(r['model'] for r in lines if r['checkpoint'] == c) for c in checkpoints]
        by_checkpoint = len(set(models)) < len(models)
        for checkpoint, model in zip(checkpoints, models):
            curve = sorted(
                (r['k'], 100 * r['md_rel'])
                for r in lines
                if r['checkpoint'] == checkpoint and r['md_rel'] is not None
            )
            label = Path(checkpoint).stem if by_checkpoint else model
            ax.plot(*zip(*curve), 'o-', label=label)
        ax.axhline(0, color='grey', lw=0.5)
        ax.set_xticks(sorted({r['k'] for r in lines}))
        ax.set_title(f'{task}: {noise}', fontsize=10)
        ax.set_xlabel('k')
        ax.set_ylabel('MD change (%)')
        ax.legend(fontsize=7)
    return save(fig, path)


def plot_explanation(
    path: str | Path,
    grid: np.ndarray,
    entities: EntityTable,
    title: str,
    values: np.ndarray,
    relation_map: np.ndarray,
    goal,
    pairs: list[dict],
    words: list[str],
    true_values: np.ndarray | None = None,
    true_goal=None,
) -> Path:
    """
    Plot a model's grounding of one instruction and why (the paper's Figures 3 and 4).

    Top: the map, the predicted and (when known) true value maps, |Z1|, goals marked. Bottom:
    for each pair of `pairs` ({'cell', 'neighbour', 'names', 'score', 'attention'}), numbered
    on the map, the attention over `words` (None: the model has none, its text is the mean).
    """
    heat = [(values, 'predicted values', 'viridis'), (np.abs(relation_map), '|Z1|', 'magma')]
    if true_values is not None:
        heat.insert(1, (true_values, 'true values', 'viridis'))
    columns = max(len(heat) + 1, len(pairs), 1)
    fig, axes = plt.subplots(2, columns, figsize=(3.6 * columns, 7.2), squeeze=False)
    draw_map(axes[0][0], grid, entities)
    draw_heat_maps(fig, [(ax, *panel) for ax, panel in zip(axes[0][1:], heat)])
    for ax in axes[0][:len(heat) + 1]:
        mark_goals(ax, goal, true_goal, grid.shape)
    for number, pair in enumerate(pairs, 1):
        (r, c), (nr, nc) = pair['cell'], pair['neighbour']
        axes[0][0].annotate(
            '', xy=(nc, nr), xytext=(c, r), arrowprops={'arrowstyle': '->', 'color': 'crimson'}
        )
        axes[0][0].text(c - 0.45, r - 0.2, str(number), color='crimson', fontsize=8)
        ax = axes[1][number - 1]
        names = pair['names']
        ax.set_title(
            f'{number}: {names[0]} {pair["cell"]} -> {names[1]} {pair["neighbour"]}\n'
            f'r = {pair["score"]:+.2f}',
            fontsize=8,
        )
        if pair['attention'] is None:
            ax.text(0.5, 0.5, 'no attention:\nmean of the words', ha='center', va='center')
            ax.set_axis_off()
            continue
        ax.bar(range(len(words)), pair['attention'], color='teal')
        ax.axhline(1 / len(words), color='grey', ls='--', lw=1, label='uniform')
        ax.set_xticks(range(len(words)))
        ax.set_xticklabels(words, rotation=60, ha='right', fontsize=7)
        ax.set_ylim(0, 1.3 * max(pair['attention'].max(), 1 / len(words)))
        ax.set_ylabel('attention')
        ax.legend(fontsize=7)
    for ax in [*axes[0][len(heat) + 1:], *axes[1][len(pairs):]]:
        ax.set_axis_off()
    fig.suptitle(title, fontsize=10)
    return save(fig, path)
