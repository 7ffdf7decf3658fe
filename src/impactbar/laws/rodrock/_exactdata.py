"""The data of an exact blow (:func:`~impactbar.laws.rodrock.exact.exact_blow`): the piston's waves at
impact and the drive on its far end, checked, with their exponents, their scale and their terms as
the wave-piece pool holds them. A drive of many pieces (a circuit's force, one cubic per step of its
integrator: :mod:`~impactbar.laws.rodrock.coupled_exact`) is checked and converted all pieces at
once."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import _exactpieces as P

__all__: list[str] = []


class _ChannelTerms(NamedTuple):
    """An initial channel's piece as the pool's terms: each term's key (the exponent's slot and
    degree) and coefficient."""
    keys: np.ndarray
    coefs: np.ndarray


class _DriveTerms(NamedTuple):
    """The drive as the pool's terms: its pieces' starts, their terms' keys and coefficients one
    piece after another, and each piece's count of terms."""
    starts: np.ndarray
    keys: np.ndarray
    coefs: np.ndarray
    sizes: np.ndarray


class _Terms(NamedTuple):
    """The data as the pool's terms: each initial channel's, and the drive's (None: no drive)."""
    initial: list
    drive: _DriveTerms | None


def _as_they_come(x) -> bool:
    """Whether the piece ``x`` is three one-dimensional arrays, taken as they come."""
    if len(x) != 3:
        return False
    e, d, c = x
    nd = np.ndarray
    return type(e) is nd and type(d) is nd and type(c) is nd and e.ndim == d.ndim == c.ndim == 1


class _Drive:
    """The drive of :func:`exact_blow` checked, with its exponents and the bound of its values
    (made once for the many blows of one :class:`~impactbar.laws.rodrock.exactmap.ExactBlowMap`):
    its pieces' terms one after another (``flat``: exponents, degrees, coefficients, and the
    pieces' sizes), as a drive of many pieces (a circuit's force, one cubic per integrator step)
    is checked and converted best, all pieces at once."""

    def __init__(self, drive):
        starts, pieces = drive
        starts = np.asarray(starts, dtype=float)
        parts = [x if _as_they_come(x) else tuple(np.atleast_1d(np.asarray(a)) for a in x) for x in pieces]
        if not all(e.ndim == 1 and e.shape == d.shape == c.shape for e, d, c in parts):
            raise ValueError("drive: each piece is (exps, degs, coefs), arrays of one length")
        if starts.ndim != 1 or starts.size != len(parts) or starts.size == 0 or \
                not np.all(np.isfinite(starts)) or starts[0] > 0.0 or np.any(np.diff(starts) <= 0.0):
            raise ValueError("drive must be (starts, pieces): increasing finite starts, the first "
                             "<= 0, one piece each")
        e, d, c = (np.concatenate([x[i] for x in parts]) for i in range(3))
        e, d, c = e.astype(complex), d.astype(np.int64), c.astype(complex)
        if not (np.all(np.isfinite(e)) and np.all(np.isfinite(c)) and np.all((d >= 0) & (d < P.DC))):
            raise ValueError(f"drive: exponents and coefficients must be finite, degrees in [0, {P.DC})")
        sizes = np.array([exps.size for exps, _, _ in parts], dtype=np.int64)
        self.flat = (e, d, c, sizes)
        self.starts = starts
        _, first = np.unique(e, return_index=True)  # (its exponents once each, in the order they come)
        self.exponents = e[np.sort(first)].tolist()
        # (the sup of sum c tau^d over a piece's span: a polynomial's pieces are short, and their
        # monomials' coefficients large; the forces' scale must not take them as its size)
        spans = np.diff(np.append(starts, starts[-1] + 1.0))
        self.bound = float(_piece_sums(np.abs(c) * np.repeat(spans, sizes) ** d, sizes).max())


def _piece_sums(x, sizes):
    """The sums of consecutive runs of ``x`` of the given sizes, each the float ``np.sum`` gives it
    (a run of fewer than 8 terms summed in order, as numpy does; a longer one by ``np.sum``)."""
    ends = np.cumsum(sizes)
    begins = ends - sizes
    out = np.zeros(sizes.size)
    short = (sizes > 0) & (sizes < 8)
    if np.any(short):
        rows = np.zeros((int(np.count_nonzero(short)), 7))
        at = begins[short, None] + np.arange(7)
        inside = np.arange(7) < sizes[short, None]
        rows[inside] = x[at[inside]]
        acc = rows[:, 0]
        for j in range(1, 7):
            acc = acc + rows[:, j]
        out[short] = acc
    for j in np.flatnonzero(sizes >= 8):
        out[j] = np.sum(x[begins[j]:ends[j]])
    return out


class _Data:
    """The piston's waves at impact and the drive of :func:`exact_blow`, checked, with their
    exponents and scale."""

    def __init__(self, initial, drive, Tp, *, trusted=False):
        init = list(initial)
        if len(init) != 2 * Tp.size:
            raise ValueError(f"initial must hold 2 pieces per piston segment ({2 * Tp.size}); got "
                             f"{len(init)}")
        # trusted: the pieces of initial_waves (arrays of the right types, finite where the modal
        # state is: checked by the caller), and a drive already checked (a _Drive)
        self.initial = init if trusted else [self._piece("initial", x) for x in init]
        exps = [e for piece_exps, _, _ in self.initial for e in piece_exps]
        bound = 0.0
        for (_e, d, c), T in zip(self.initial, np.repeat(Tp, 2), strict=True):
            bound = max(bound, float(np.sum(np.abs(c) * np.maximum(T, 1.0) ** d)))
        if drive is not None and not isinstance(drive, _Drive):
            drive = _Drive(drive)
        self.drive = drive
        if drive is not None:
            exps += drive.exponents
            bound = max(bound, drive.bound)
        self.exponents = list(dict.fromkeys(complex(e) for e in exps))
        self.scale = bound

    @staticmethod
    def _piece(name, x):
        e, d, c = (np.atleast_1d(np.asarray(a)) for a in x)
        e, c = e.astype(complex), c.astype(complex)
        d = d.astype(np.int64)
        if not (e.shape == d.shape == c.shape and e.ndim == 1):
            raise ValueError(f"{name}: each piece is (exps, degs, coefs), arrays of one length")
        if not (np.all(np.isfinite(e)) and np.all(np.isfinite(c)) and np.all((d >= 0) & (d < P.DC))):
            raise ValueError(f"{name}: exponents and coefficients must be finite, degrees in "
                             f"[0, {P.DC})")
        return e, d, c

    def terms(self, lam, scale):
        """The pieces as the pool's terms: ``(keys, coefs)`` per initial channel, and ``(starts, keys,
        coefs, sizes)`` of the drive, its pieces' terms one after another (coefficients over
        ``scale``)."""
        index = {complex(x): i for i, x in enumerate(lam)}

        def conv(piece):
            e, d, c = piece
            keys = np.array([index[complex(x)] * P.DC for x in e], dtype=np.int64) + d
            return _ChannelTerms(keys, c / scale)

        init = [conv(x) for x in self.initial]
        drv = None
        if self.drive is not None:
            e, d, c, sizes = self.drive.flat
            distinct, where = np.unique(e, return_inverse=True)
            slot = np.array([index[complex(x)] * P.DC for x in distinct], dtype=np.int64)
            drv = _DriveTerms(self.drive.starts, slot[where.ravel()] + d, c / scale, sizes)
        return _Terms(init, drv)
