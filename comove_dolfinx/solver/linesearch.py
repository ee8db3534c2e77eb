"""Line searches along a Newton correction du (docs/theory.md section 7.1).

"residual": the full step if it is admissible and lowers ||R||, otherwise halved (up to
``backtracks`` times) until ||R|| <= (1 - 1e-4 alpha) r_old (Armijo), keeping the best admissible
step when none does; with contact terms the test starts after the first ``free_its`` corrections of
an increment (it stops active-set and stick/slip cycling, and ||R|| is not monotone along a converging
path of a rotating slender body). "energy": Crisfield's search for the root of s(a) = du . R(u + a du)
by regula falsi (Non-linear Finite Element Analysis of Solids and Structures, vol. 1, 9.3), for bodies
whose corrections overshoot (plastic hinges). An inadmissible trial (det F <= 0, an S-R split out of
range) is halved in both.
"""
from __future__ import annotations

import numpy as np

from ..mechanics.model import InvertedElement, ReturnMapFailure


class LineSearches:
    """Mixed into Newton: needs model, settings, b (= -R), _b_old, residual(), and the iterate's
    and the correction's arrays _u, _du and the correction's PETSc vector _du_vec."""

    def _trial(self, u0: np.ndarray, alpha: float):
        """u = u0 + alpha du and its ||R||; (None, error) if the iterate is inadmissible."""
        np.multiply(self._du, alpha, out=self._u)
        self._u += u0
        self._last_trial = None
        try:
            r = self.residual(again=True)          # a new iterate: no need to compare it
        except (InvertedElement, ReturnMapFailure) as e:
            return None, e
        self._last_trial = (alpha, r)
        return r, None

    def _settle(self, u0: np.ndarray, alpha: float | None, r_old: float, err):
        """End a search on the chosen step (or back at u0 when no trial was admissible); the model
        already holds the chosen step when it was the last trial."""
        if alpha is None:
            self._u[:] = u0
            return r_old, 0.0, err
        if self._last_trial is not None and self._last_trial[0] == alpha:
            return self._last_trial[1], alpha, None
        r, _ = self._trial(u0, alpha)
        return r, alpha, None

    def _line_search(self, r_old: float, armijo: bool = True):
        """Move u along the Newton correction du: the full step if it is admissible and lowers
        ||R||; otherwise halve it (up to ``backtracks`` times) until ||R|| <= (1 - 1e-4 alpha) r_old,
        keeping the best admissible step when none does. Returns (||R||, alpha, error or None)."""
        u0 = self._u.copy()
        best, alpha, err = None, 1.0, None
        for _ in range(self.settings.backtracks + 1):
            r, e = self._trial(u0, alpha)
            if r is None:
                err, alpha = e, 0.5 * alpha
                continue
            if best is None or r < best[0]:
                best = (r, alpha)
            if not (self.line_search and armijo) or r <= (1.0 - 1e-4 * alpha) * r_old:
                return r, alpha, None
            alpha *= 0.5
        return self._settle(u0, best[1] if best else None, r_old, err)

    def _energy_search(self, r_old: float):
        """Crisfield's line search on s(a) = du . R(u + a du), s(0) < 0 along a descent direction:
        the full step if |s(1)| <= eta |s(0)| or s(1) still has the sign of s(0) (no extrapolation);
        otherwise regula falsi on the bracket of the sign change (at most ``backtracks`` more
        trials), keeping the trial of smallest |s|. An inadmissible trial is halved.
        Returns (||R||, alpha, error or None)."""
        st = self.settings
        u0 = self._u.copy()
        s0 = -self._b_old.dot(self._du_vec)           # b = -R
        lo, hi = (0.0, s0), None
        alpha, err, best = 1.0, None, None
        for _ in range(st.backtracks + 1):
            r, e = self._trial(u0, alpha)
            if r is None:
                err, hi = e, None
                alpha = 0.5 * (lo[0] + alpha)
                continue
            s1 = -self.b.dot(self._du_vec)
            if best is None or abs(s1) < best[0]:
                best = (abs(s1), alpha)
            if abs(s1) <= st.energy_eta * abs(s0) or (s1 * s0 > 0 and hi is None):
                return r, alpha, None
            if s1 * s0 > 0:
                lo = (alpha, s1)
            else:
                hi = (alpha, s1)
            a = lo[0] + (hi[0] - lo[0]) * lo[1] / (lo[1] - hi[1])
            width = hi[0] - lo[0]
            alpha = min(max(a, lo[0] + 0.1 * width), hi[0] - 0.1 * width)
        return self._settle(u0, best[1] if best else None, r_old, err)
