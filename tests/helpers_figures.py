"""Text that overlaps other text or leaves the figure, read from matplotlib's own layout.

:func:`text_problems` draws a figure (so that its layout is final) and compares the window
extents of every piece of text a reader sees: titles, axis labels, tick labels that are drawn,
annotations, legend entries and titles, figure-level texts. Two texts overlap when their boxes
share more than :data:`SLACK` pixels each way; a text leaves the figure when its box crosses the
figure's edge (only for figures laid out by matplotlib: the others are cropped to their content
when saved). :func:`watch_figures` records the problems of every figure saved while it is active.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

#: Boxes may touch or share this many pixels (at the figure's dpi) without counting as an overlap.
SLACK = 1.5


def _drawn_ticks(axis):
    try:
        return axis._update_ticks()  # the ticks inside the view, as drawn
    except AttributeError:  # pragma: no cover - older matplotlib
        return axis.get_major_ticks()


def _texts(fig):
    """``(description, Text)`` of every visible non-empty text of the figure."""
    out, ids = [], set()

    def add(what, t):
        if t is not None and id(t) not in ids and t.get_visible() and t.get_text().strip():
            ids.add(id(t))
            out.append((what, t))

    add("title", fig._suptitle)
    for t in fig.texts:
        add("figure text", t)
    add("figure x label", getattr(fig, "_supxlabel", None))
    add("figure y label", getattr(fig, "_supylabel", None))
    for lg in fig.legends:
        add("legend title", lg.get_title())
        for t in lg.get_texts():
            add("legend", t)
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible():
            continue
        where = f"axes {k}"
        for t in (ax.title, ax._left_title, ax._right_title):
            add(f"{where} title", t)
        add(f"{where} x label", ax.xaxis.label)
        add(f"{where} y label", ax.yaxis.label)
        add(f"{where} x offset", ax.xaxis.offsetText)
        add(f"{where} y offset", ax.yaxis.offsetText)
        for axis, name in ((ax.xaxis, "x"), (ax.yaxis, "y")):
            for tick in _drawn_ticks(axis):
                for lab in (tick.label1, tick.label2):
                    add(f"{where} {name} tick", lab)
        for t in ax.texts:
            add(f"{where} text", t)
        lg = ax.get_legend()
        if lg is not None:
            add(f"{where} legend title", lg.get_title())
            for t in lg.get_texts():
                add(f"{where} legend", t)
    return out


def _box(t, renderer):
    box = t.get_window_extent(renderer)
    if t.get_clip_on() and t.get_clip_box() is not None:  # a clipped text shows only inside its box
        clip = t.get_clip_box()
        x0, y0 = max(box.x0, clip.x0), max(box.y0, clip.y0)
        x1, y1 = min(box.x1, clip.x1), min(box.y1, clip.y1)
        if x1 <= x0 or y1 <= y0:
            return None
        from matplotlib.transforms import Bbox

        box = Bbox([[x0, y0], [x1, y1]])
    return box


def text_problems(fig) -> list[str]:
    """Every overlap between two texts of ``fig``, and every text leaving it, in words."""
    from matplotlib.text import Annotation

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    problems, texts = [], _texts(fig)
    for what, t in texts:  # an annotation whose point is outside its axes is silently not drawn
        if isinstance(t, Annotation) and not t._check_xy(renderer):
            problems.append(f"{what} {t.get_text()!r} is not drawn: its point lies outside the axes")
    boxes = [(what, t, b) for what, t in texts if not (isinstance(t, Annotation) and not t._check_xy(renderer))
             and (b := _box(t, renderer)) is not None]
    for i, (wa, ta, a) in enumerate(boxes):
        for wb, tb, b in boxes[i + 1:]:
            dx = min(a.x1, b.x1) - max(a.x0, b.x0)
            dy = min(a.y1, b.y1) - max(a.y0, b.y0)
            if dx > SLACK and dy > SLACK:
                problems.append(f"{wa} {ta.get_text()!r} overlaps {wb} {tb.get_text()!r}")
    for k, ax in enumerate(fig.axes):  # a label of a point in the data belongs inside its axes
        if not ax.get_visible():
            continue
        frame = ax.get_window_extent(renderer)
        for t in ax.texts:
            anchored = t.xycoords == "data" if isinstance(t, Annotation) else t.get_transform() == ax.transData
            b = _box(t, renderer) if anchored and t.get_visible() and t.get_text().strip() else None
            if b is not None and not (isinstance(t, Annotation) and not t._check_xy(renderer)) and (
                    b.x0 < frame.x0 - SLACK or b.y0 < frame.y0 - SLACK or b.x1 > frame.x1 + SLACK
                    or b.y1 > frame.y1 + SLACK):
                problems.append(f"axes {k} text {t.get_text()!r} (a label of a point) lies outside its axes")
    if fig.get_layout_engine() is not None:
        W, H = fig.bbox.width, fig.bbox.height
        for what, t, b in boxes:
            if b.x0 < -SLACK or b.y0 < -SLACK or b.x1 > W + SLACK or b.y1 > H + SLACK:
                problems.append(f"{what} {t.get_text()!r} leaves the figure")
    return problems


@contextlib.contextmanager
def watch_figures(monkeypatch):
    """While active, every figure saved is checked first: yields ``{png name: [problems]}``."""
    from matplotlib.figure import Figure

    seen: dict[str, list[str]] = {}
    real = Figure.savefig

    def checked(self, fname, *args, **kwargs):
        seen[Path(str(fname)).name.removesuffix(".part")] = text_problems(self)
        return real(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", checked)
    yield seen
