# Copyright 2026 spatial_grounding_ros developers
#
# Use of this source code is governed by an MIT-style
# license that can be found in the LICENSE file or at
# https://opensource.org/licenses/MIT.

"""
ShapeWorld data: images of shapes and true-or-false spatial statements about them.

The paper's classification task (section 4, appendix B), generated here, seeded, with no download:
64x64 RGB images of 4 or 5 non-overlapping objects, each one of 8 shapes in one of 8 colours, on
black; one statement per image relating two objects by shape, colour or both ("a red ellipse is
to the right of an ellipse", "a green shape is above a cross"), labelled true or false.

What a statement means, exactly (the tests read scenes against it independently):
- "X is to the left of Y" is true when some object matching X has its centre left of the centre
  of some other object matching Y (and likewise right, above, below; x grows east, y south).
- No object matches both X and Y: otherwise two such objects would make every relation true.
- Every pair of an X object and a Y object is at least MARGIN pixels apart along the relation's
  axis, so no label hangs on a near-tie.
- It is false when no object matches X, or none matches Y, or the relation fails for every pair.
  X and Y are never nested ("a red circle" and "a red shape", or twice "a circle"): such a
  statement could never be true, so its words alone would give the label away.
- False statements come from the sources of ShapeWorld's own generator (its captioners' incorrect
  modes, github.com/AlexKuhnle/ShapeWorld, as configured for the data of Andreas et al. 2017 that
  the paper used): a true statement with its relation inverted or replaced ('relation': both
  objects exist, the relation fails), or with its subject's or its reference's description
  changed ('subject', 'reference': the shape, the colour or both replaced, for a description
  naming both half of the time by values the image has) so that no object fits it. A fraction
  `absent` of the false statements (ABSENT in the splits, 0 in the all-plausible version) is of
  the last two kinds, SUBJECT of them 'subject'; each example keeps its reason ('true' or the
  source).
- Labels are balanced within every (description kinds, relation) stratum, so the text alone
  predicts nothing.

Splits are generated from their own seeds (9000 train / 500 test by default, the paper's sizes)
and cached as .npz under the cache directory, so a rerun reads them instead of drawing them
again.
"""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path

import numpy as np

IMAGE = 64  # pixels per side
SHAPES = (
    'square', 'rectangle', 'triangle', 'pentagon', 'cross', 'circle', 'semicircle', 'ellipse'
)
COLOURS = {
    'red': (1.0, 0.0, 0.0),
    'green': (0.0, 1.0, 0.0),
    'blue': (0.2, 0.3, 1.0),  # pure blue is too dark on black to tell from its shade variations
    'yellow': (1.0, 1.0, 0.0),
    'magenta': (1.0, 0.0, 1.0),
    'cyan': (0.0, 1.0, 1.0),
    'white': (1.0, 1.0, 1.0),
    'gray': (0.5, 0.5, 0.5),
}
COLOUR_NAMES = tuple(COLOURS)
# relation -> (axis of the centres compared: 0 = x, 1 = y, sign): "a is <rel> b" holds when
# sign * (centre_a - centre_b) > 0
RELATIONS = {
    'to the left of': (0, -1),
    'to the right of': (0, 1),
    'above': (1, -1),
    'below': (1, 1),
}
DESCRIPTIONS = ('shape', 'colour', 'both')  # naming an object: "a circle", "a red shape", ...
OBJECTS = (4, 5)  # objects per image
SIZES = (10, 14)  # object bounding-box side in pixels, inclusive range
GAP = 2  # free pixels between bounding boxes
SHADE = (0.75, 1.0)  # each object's colour is scaled by a random shade in this range
MARGIN = 4.0  # pixels: every compared pair of centres is at least this far apart on the axis
SPLIT_SIZES = {'train': 9000, 'test': 500}
SPLIT_SEEDS = {'train': 0, 'test': 1}  # the splits are drawn from different streams
VERSION = 3  # part of the cache file name: bump it when generation changes
# The splits' mix of false statements: ShapeWorld's procedure for the data the paper used (its
# existential captioner changes the subject in half of the false captions, its relation
# captioner the relation, its direction or the reference in a sixth each), run on these scenes,
# keeps 36% false by the relation, 49% naming an absent subject and 16% an absent reference
# (docs/shapeworld.md): a third, a half and a sixth here
ABSENT = 2 / 3  # share of false statements that name an absent object
SUBJECT = 3 / 4  # share of those whose absent object is the subject
REASONS = ('true', 'relation', 'subject', 'reference')  # why a statement has its label
EXISTING = 0.5  # share of changed descriptions naming both that take values the image holds
# object rows: shape index, colour index, box left x, box top y, box side; -1 rows pad to 5
FIELDS = ('shape', 'colour', 'x0', 'y0', 'size')
# inserted by the textual noise: verbs, articles and objects that are not ShapeWorld's
NOISE_WORDS = ('go', 'reach', 'locate', 'move', 'find', 'the', 'a', 'car', 'stone', 'tree')
NOISE_PATCH = 6  # side of an observational-noise patch, in pixels


@dataclass
class ShapeWorldSet:
    """Aligned examples: images (N,64,64,3) uint8, statements, labels (N,) 1 = true, objects."""

    name: str
    images: np.ndarray
    statements: list[str]
    labels: np.ndarray
    objects: np.ndarray  # (N, 5, 5) int64, rows as FIELDS, -1 where an image has 4 objects
    reasons: list[str]  # one of REASONS: 'true', or what makes the statement false

    def __len__(self) -> int:
        return len(self.statements)

    def subset(self, index, name: str | None = None) -> 'ShapeWorldSet':
        index = np.asarray(index, dtype=np.int64)
        return ShapeWorldSet(
            name or self.name,
            self.images[index],
            [self.statements[i] for i in index],
            self.labels[index],
            self.objects[index],
            [self.reasons[i] for i in index],
        )


N_ATTRIBUTES = len(SHAPES) + len(COLOURS) + len(SHAPES) * len(COLOURS)


def scene_attributes(objects: np.ndarray) -> np.ndarray:
    """
    Return which shapes, colours and shape-colour pairs each image holds: t-VGG's scene labels.

    (N, 5, 5) objects -> (N, N_ATTRIBUTES) float32, 8 shapes, 8 colours and 64 pairs.
    """
    n_shapes, n_colours = len(SHAPES), len(COLOURS)
    out = np.zeros((len(objects), N_ATTRIBUTES), np.float32)
    rows, slots = np.nonzero(objects[:, :, 0] >= 0)
    shape, colour = objects[rows, slots, 0], objects[rows, slots, 1]
    out[rows, shape] = 1
    out[rows, n_shapes + colour] = 1
    out[rows, n_shapes + n_colours + shape * n_colours + colour] = 1
    return out


# --- drawing ------------------------------------------------------------------------------


def _pentagon(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Inside a regular pentagon of radius 1, a vertex at the top: inside all 5 edges."""
    normals = -np.pi / 2 + np.pi / 5 + 2 * np.pi * np.arange(5) / 5
    inside = [u * np.cos(a) + v * np.sin(a) <= np.cos(np.pi / 5) for a in normals]
    return np.logical_and.reduce(inside)


# u, v in (-1, 1) over the bounding box, v pointing down (south)
SHAPE_MASKS = {
    'square': lambda u, v: (abs(u) <= 0.9) & (abs(v) <= 0.9),
    'rectangle': lambda u, v: (abs(u) <= 1.0) & (abs(v) <= 0.5),
    'triangle': lambda u, v: abs(u) <= (v + 1) / 2,
    'pentagon': _pentagon,
    'cross': lambda u, v: ((abs(u) <= 0.35) | (abs(v) <= 0.35)),
    'circle': lambda u, v: u**2 + v**2 <= 1.0,
    'semicircle': lambda u, v: (u**2 + (v - 0.5) ** 2 <= 1.0) & (v <= 0.5),
    'ellipse': lambda u, v: u**2 + (v / 0.55) ** 2 <= 1.0,
}


def shape_mask(shape: int, size: int) -> np.ndarray:
    """(size, size) bool: the pixels of a shape drawn in a box of that side."""
    centres = (np.arange(size) + 0.5) / size * 2 - 1  # pixel centres in (-1, 1)
    v, u = np.meshgrid(centres, centres, indexing='ij')
    return SHAPE_MASKS[SHAPES[shape]](u, v)


def centres(objects: np.ndarray) -> np.ndarray:
    """(..., 2) x, y of each object's box centre in pixels."""
    return objects[..., 2:4] + (objects[..., 4:5] - 1) / 2


def render(objects: np.ndarray, shades: np.ndarray) -> np.ndarray:
    """(64, 64, 3) uint8 image of the objects (rows of FIELDS, -1 rows skipped) on black."""
    image = np.zeros((IMAGE, IMAGE, 3), dtype=np.float32)
    for (shape, colour, x0, y0, size), shade in zip(objects, shades):
        if shape < 0:
            continue
        box = image[y0:y0 + size, x0:x0 + size]
        box[shape_mask(shape, size)] = np.array(COLOURS[COLOUR_NAMES[colour]]) * shade
    return np.round(image * 255).astype(np.uint8)


def random_scene(rng: np.random.Generator) -> np.ndarray:
    """(n, 5) objects of random shape, colour and size, boxes GAP pixels apart, n in OBJECTS."""
    n = int(rng.integers(OBJECTS[0], OBJECTS[1] + 1))
    while True:  # a dead end (no room left) is rare: start the scene over
        placed = []
        for _ in range(n):
            for _ in range(100):
                size = int(rng.integers(SIZES[0], SIZES[1] + 1))
                x0, y0 = rng.integers(0, IMAGE - size + 1, size=2)
                if all(
                    x0 + size + GAP <= ox or ox + osize + GAP <= x0
                    or y0 + size + GAP <= oy or oy + osize + GAP <= y0
                    for _, _, ox, oy, osize in placed
                ):
                    kind = rng.integers(len(SHAPES)), rng.integers(len(COLOURS))
                    placed.append((*kind, x0, y0, size))
                    break
        if len(placed) == n:
            return np.array(placed, dtype=np.int64)


# --- statements ---------------------------------------------------------------------------


def describe(obj: np.ndarray, kind: str) -> tuple[int, int]:
    """(shape, colour) that a description of `kind` names; -1 = not named."""
    return (int(obj[0]) if kind != 'colour' else -1, int(obj[1]) if kind != 'shape' else -1)


def matches(objects: np.ndarray, description: tuple[int, int]) -> np.ndarray:
    """Bool per object: does the description fit it (-1 rows never fit)."""
    shape, colour = description
    fits = objects[:, 0] >= 0
    if shape >= 0:
        fits &= objects[:, 0] == shape
    if colour >= 0:
        fits &= objects[:, 1] == colour
    return fits


def phrase(description: tuple[int, int]) -> str:
    """Name a description: 'a red circle', 'an ellipse', 'a gray shape'."""
    shape, colour = description
    words = ([COLOUR_NAMES[colour]] if colour >= 0 else []) + [
        SHAPES[shape] if shape >= 0 else 'shape'
    ]
    return ('an ' if words[0][0] in 'aeiou' else 'a ') + ' '.join(words)


def statement(subject: tuple[int, int], relation: str, reference: tuple[int, int]) -> str:
    return f'{phrase(subject)} is {relation} {phrase(reference)}'


INVERSE = {
    'to the left of': 'to the right of',
    'to the right of': 'to the left of',
    'above': 'below',
    'below': 'above',
}


def converse(text: str) -> str:
    """'X is left of Y' -> 'Y is right of X': the same claim, so the same label."""
    for relation in RELATIONS:
        subject, sep, reference = text.partition(f' is {relation} ')
        if sep:
            return f'{reference} is {INVERSE[relation]} {subject}'
    raise ValueError(f'not a ShapeWorld statement: {text!r}')


def truth(
    objects: np.ndarray, subject: tuple[int, int], relation: str, reference: tuple[int, int]
) -> bool | None:
    """Whether the statement holds; None when it is not a fair question (see module docstring)."""
    a, b = matches(objects, subject), matches(objects, reference)
    if not a.any() or not b.any() or (a & b).any():
        return None
    axis, sign = RELATIONS[relation]
    pos = centres(objects)[:, axis]
    diff = sign * (pos[a][:, None] - pos[b][None, :])  # every (subject, reference) pair
    if (abs(diff) < MARGIN).any():
        return None
    return bool((diff > 0).any())


def nested(a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Whether every object fitting one description fits the other ('a circle', 'a red circle')."""

    def within(x, y):
        return all(y[k] < 0 or y[k] == x[k] for k in range(2))

    return within(a, b) or within(b, a)


def reason(
    objects: np.ndarray, subject: tuple[int, int], relation: str, reference: tuple[int, int]
) -> str | None:
    """
    Return 'true' or why the statement is false (REASONS); None when it is no fair question.

    'subject' / 'reference': no object fits that side (the other side fits one); 'relation':
    both fit objects, the relation fails for every pair (truth); nested sides are not fair.
    """
    if nested(subject, reference):
        return None
    a, b = matches(objects, subject).any(), matches(objects, reference).any()
    if a and b:
        holds = truth(objects, subject, relation, reference)
        return None if holds is None else 'true' if holds else 'relation'
    return 'subject' if b else 'reference' if a else None


def changed_description(
    description: tuple[int, int], objects: np.ndarray, rng: np.random.Generator
) -> tuple[int, int] | None:
    """
    Return the description with a named attribute replaced, ShapeWorld's incorrect type.

    Naming shape and colour, the shape, the colour or both change (a third each, its captioner's
    modes), with probability EXISTING to values the image's objects have (its "existing
    attribute" mode, never for a description naming one attribute), else to any; each new value
    differs from the old. None: no such value.
    """
    named = [k for k in range(2) if description[k] >= 0]
    which = named if len(named) == 1 else [[0], [1], [0, 1]][rng.integers(3)]
    existing = len(named) == 2 and rng.random() < EXISTING
    new = list(description)
    for k in which:
        pool = objects[:, k] if existing else np.arange(len(SHAPES) if k == 0 else len(COLOURS))
        pool = np.unique(pool[(pool >= 0) & (pool != description[k])])
        if not len(pool):
            return None
        new[k] = int(rng.choice(pool))
    return new[0], new[1]


def _example(rng, kinds, relation, want: str):
    """(scene objects, subject, reference) of a statement whose reason() is `want`."""
    while True:
        objects = random_scene(rng)
        for _ in range(20):
            s, r = rng.choice(len(objects), size=2, replace=False)
            sides = [describe(objects[s], kinds[0]), describe(objects[r], kinds[1])]
            if want in ('subject', 'reference'):  # change a side of a true statement
                if truth(objects, sides[0], relation, sides[1]) is not True:
                    continue
                side = REASONS.index(want) - 2
                sides[side] = changed_description(sides[side], objects, rng)
                if sides[side] is None:
                    continue
            if reason(objects, sides[0], relation, sides[1]) == want:
                return objects, sides[0], sides[1]


def generate(
    n: int,
    seed: int = 0,
    name: str = 'shapeworld',
    descriptions: tuple = DESCRIPTIONS,
    absent: float = ABSENT,
) -> ShapeWorldSet:
    """
    N examples, half true, half false, in every (description kinds, relation) stratum.

    Each example draws its stratum and label first, and a false one its reason (a fraction
    `absent` 'subject' or 'reference', SUBJECT of them 'subject', the rest 'relation'), then
    scenes and object
    pairs until a statement of that stratum has that reason. `descriptions` are the kinds of
    naming drawn for each side (('colour',): only "a red shape is above a green shape").
    A false statement with an absent side is a true statement of the stratum with that side's
    description changed (changed_description), as ShapeWorld's generator makes them; one false
    by its relation is a true statement with its relation inverted, which is the same as two
    objects for which the stated relation fails (no near-ties, see truth).
    """
    if not 0 <= absent <= 1:
        raise ValueError(f'absent is a fraction of the false statements, got {absent}')
    if not set(descriptions) <= set(DESCRIPTIONS) or not descriptions:
        raise ValueError(f'descriptions {descriptions} are not some of {DESCRIPTIONS}')
    rng = np.random.default_rng(seed)
    relations = list(RELATIONS)
    images, statements, labels, rows, reasons = [], [], [], [], []
    for i in range(n):
        label = bool(i % 2)  # exactly half true; strata are drawn independently of it
        kinds = tuple(descriptions[rng.integers(len(descriptions))] for _ in range(2))
        relation = relations[rng.integers(len(relations))]
        want = 'true' if label else 'relation'
        if not label and absent and rng.random() < absent:
            want = 'subject' if rng.random() < SUBJECT else 'reference'
        objects, subject, reference = _example(rng, kinds, relation, want)
        images.append(render(objects, rng.uniform(*SHADE, size=len(objects))))
        statements.append(statement(subject, relation, reference))
        labels.append(int(label))
        reasons.append(want)
        padded = np.full((OBJECTS[1], len(FIELDS)), -1, dtype=np.int64)
        padded[: len(objects)] = objects
        rows.append(padded)
    return ShapeWorldSet(
        name, np.stack(images), statements, np.array(labels), np.stack(rows), reasons
    )


# --- splits on disk -----------------------------------------------------------------------


def default_cache_dir() -> Path:
    """$SPATIAL_GROUNDING_CACHE, else ~/.cache/spatial_grounding_ros."""
    env = os.environ.get('SPATIAL_GROUNDING_CACHE')
    return Path(env) if env else Path.home() / '.cache' / 'spatial_grounding_ros'


def load_split(
    split: str,
    cache_dir: str | Path | None = None,
    n: int | None = None,
    seed: int = 0,
    descriptions: tuple = DESCRIPTIONS,
    absent: float = ABSENT,
) -> ShapeWorldSet:
    """
    Return a split, generating it into the cache the first time.

    The file name holds the generator version, the split, its size, the seed, the kinds of
    naming when not all three and the fraction `absent` (absent0.667 for the splits, absent0
    for the all-plausible version), so a change of any of them makes a new file rather than
    reading a stale one.
    """
    if split not in SPLIT_SIZES:
        raise ValueError(f'ShapeWorld has no split {split!r}; use one of {", ".join(SPLIT_SIZES)}')
    n = SPLIT_SIZES[split] if n is None else n
    if n < 1:
        raise ValueError(f'ShapeWorld split size must be positive, got {n}')
    kinds = '' if tuple(descriptions) == DESCRIPTIONS else '-' + '-'.join(descriptions)
    kinds += f'-absent{absent:.3g}'
    name = f'shapeworld-{split}{kinds}'
    file_name = f'shapeworld-v{VERSION}-{split}{kinds}-{n}-seed{seed}.npz'
    path = Path(cache_dir or default_cache_dir()) / file_name
    if path.is_file():
        try:
            with np.load(path) as f:
                return ShapeWorldSet(
                    name, f['images'], [str(s) for s in f['statements']], f['labels'],
                    f['objects'], [str(s) for s in f['reasons']],
                )
        except Exception as exc:  # numpy raises many types on a truncated or foreign file
            raise ValueError(
                f'{path}: corrupt ShapeWorld cache ({type(exc).__name__}); delete it to regenerate'
            ) from exc
    data = generate(n, 1000 * seed + SPLIT_SEEDS[split], name, descriptions, absent)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + f'.{os.getpid()}.tmp.npz')
    np.savez_compressed(
        tmp,
        images=data.images,
        statements=np.array(data.statements),
        labels=data.labels,
        objects=data.objects,
        reasons=np.array(data.reasons),
    )
    tmp.replace(path)  # atomic: a parallel run never reads half a file
    return data


# --- noise (the paper's robustness study, appendix C) -------------------------------------


def image_noise(
    images: np.ndarray, objects: np.ndarray, k: int, rng: np.random.Generator
) -> np.ndarray:
    """
    Float images in [0, 1] with k patches of N(0, 1) pixels each, the paper's noise patches.

    Patches (NOISE_PATCH pixels square) go on background only, clear of every object's box
    and of each other, so the statement's truth is unchanged.
    """
    out = images.astype(np.float32) / 255
    side = NOISE_PATCH
    for n in range(len(out)):
        taken = np.zeros((IMAGE, IMAGE), dtype=bool)
        for shape, _, x0, y0, size in objects[n]:
            if shape >= 0:
                taken[max(y0 - 1, 0):y0 + size + 1, max(x0 - 1, 0):x0 + size + 1] = True
        placed = 0
        for _ in range(200 * k):
            if placed == k:
                break
            x0, y0 = rng.integers(0, IMAGE - side + 1, size=2)
            if taken[y0:y0 + side, x0:x0 + side].any():
                continue
            out[n, y0:y0 + side, x0:x0 + side] = rng.standard_normal((side, side, 3))
            taken[y0:y0 + side, x0:x0 + side] = True
            placed += 1
    return out


def text_noise(statements: list[str], k: int, rng: np.random.Generator) -> list[str]:
    """Insert k random NOISE_WORDS at one random position of each statement, as the paper."""
    out = []
    for text in statements:
        words = text.split()
        at = int(rng.integers(len(words) + 1))
        inserted = [NOISE_WORDS[i] for i in rng.integers(len(NOISE_WORDS), size=k)]
        out.append(' '.join(words[:at] + inserted + words[at:]))
    return out
