"""Progress on standard error while a command runs."""

from __future__ import annotations

import sys

import click


class LazyBar:
    """A progress bar on standard error that appears only once there is progress to show
    (so that an input error is never preceded by a bar's label); none if ``quiet``."""

    def __init__(self, length: int, label: str, quiet: bool = False, **kw):
        self._args = dict(length=length, label=label, file=sys.stderr, **kw)
        self._bar = None
        self.done = 0
        self.quiet = quiet

    def __enter__(self):
        return self

    def set(self, done: int, length: int | None = None):
        if self.quiet:
            return
        if self._bar is None:
            if length is not None:
                self._args["length"] = length
            self._bar = click.progressbar(**self._args).__enter__()
        if length is not None:
            self._bar.length = length
        if done > self.done:
            self._bar.update(done - self.done)
            self.done = done

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.__exit__(*exc)
        return False
