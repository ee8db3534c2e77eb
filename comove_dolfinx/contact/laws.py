"""The contact laws as pure UFL functions of their arguments (docs/theory.md sections 6.2-6.4).

Tractions on the body are per unit reference area (per unit reference thickness in plane stress):
contact traction = p n_o + q t_o, pressure p >= 0, t_o = (-n_o[1], n_o[0]).

::

    * Penalty:  p = gamma [-g]_+.
    * Nitsche (theta = 1, 0, -1), with the nominal normal traction p(u) = n_o . (P N) of the current stress:
          R_n = -(theta/gamma) p(u) p'(u; v) + (1/gamma) [p(u) - gamma g]_+ (theta p'(u; v) - gamma n_o.v),
      which is the exact traction term -p n_o.v whenever p = [p - gamma g]_+.
    * Coulomb friction with a slip threshold s and slip increment ds (a length along t_o), with the
      tangential weight gamma_t (a stiffness per unit area, like gamma):
          penalty:  q = -P_s(gamma_t (e_n + ds)), with e_n the elastic (stick) part carried over (a length);
          Nitsche:  q = P_s(q(u) - gamma_t ds), q(u) = t_o . (P N), and the theta-terms as for the normal part;
      P_s(x) = x for |x| <= s, s sign(x) otherwise. The threshold s = mu p is the caller's: mu times a
      lagged pressure (no derivative) or mu times the pressure these functions return for the current
      iterate (the Coulomb law: UFL differentiates it with the rest).

In 3D the slip is a vector in the obstacle's tangent plane, ds = (I - n_o n_o)(du - dd), and so are the
trial traction and the stick part; P_s becomes the return to the Coulomb disc of radius s,
``P_s(x) = x`` for ``|x| <= s``, ``s x / |x|`` otherwise (the ``*_vector`` functions; in 2D they would give the
scalar laws' numbers along t_o, which stay in use there).

Each function returns the residual integrand (linear in the test function v) with what the outputs
need; none keeps state, so each can be differentiated and Taylor-tested alone.
"""
from __future__ import annotations

import ufl


def positive_part(x):
    """[x]_+, active at x = 0: a body that just touches gets contact stiffness at once."""
    return ufl.conditional(ufl.ge(x, 0.0), x, 0.0)


def clip(x, s):
    """P_s(x), the projection onto [-s, s]; ``|x| = s`` counts as stick, so with s = 0 (no pressure yet) a
    zero slip keeps the stick stiffness instead of a singular tangent."""
    return ufl.conditional(ufl.le(abs(x), s), x, s * ufl.sign(x))


def penalty_normal(g, n_o, v, gamma):
    """(residual integrand, pressure) of the penalty law."""
    p = gamma * positive_part(-g)
    return -p * ufl.dot(n_o, v), p


def nitsche_normal(g, n_o, v, gamma, theta, p_u, dp):
    """(residual integrand, pressure) of Nitsche's method; p_u the nominal normal traction of the
    current stress, dp its derivative in the direction v."""
    p = positive_part(p_u - gamma * g)
    R = p / gamma * (theta * dp - gamma * ufl.dot(n_o, v))
    if theta:
        R = -theta / gamma * p_u * dp + R
    return R, p


def penalty_friction(slip, e_n, s, t_o, v, gamma):
    """(residual integrand, tangential traction, trial value, new stick part) of penalty friction;
    ``gamma`` the tangential weight gamma_t."""
    trial = gamma * (e_n + slip)
    q_tr = clip(trial, s)
    return q_tr * ufl.dot(t_o, v), -q_tr, trial, q_tr / gamma


def nitsche_friction(slip, s, t_o, v, gamma, theta, q_u, dq):
    """(residual integrand, tangential traction, trial value) of Nitsche's friction term; ``gamma``
    the tangential weight gamma_t."""
    trial = q_u - gamma * slip
    q = clip(trial, s)
    R = q / gamma * (theta * dq - gamma * ufl.dot(t_o, v))
    if theta:
        R = -theta / gamma * q_u * dq + R
    return R, q, trial


def clip_vector(x, s):
    """P_s(x) for a vector x: the return to the disc ``|x| <= s`` (stick counted as in :func:`clip`)."""
    norm = ufl.sqrt(ufl.dot(x, x))
    return ufl.conditional(ufl.le(norm, s), 1.0, s / norm) * x, norm


def penalty_friction_vector(slip, e_n, s, v, gamma):
    """(residual integrand, tangential traction, ``|trial|``, new stick part) of penalty friction in 3D:
    ``slip`` and the stick part ``e_n`` are tangential vectors (lengths), the traction is a vector."""
    trial = gamma * (e_n + slip)
    q_tr, norm = clip_vector(trial, s)
    return ufl.dot(q_tr, v), -q_tr, norm, q_tr / gamma


def nitsche_friction_vector(slip, s, v, gamma, theta, q_u, dq):
    """(residual integrand, tangential traction, ``|trial|``) of Nitsche's friction term in 3D: ``q_u``
    the tangential part of the nominal traction P N, ``dq`` its derivative in the direction v."""
    trial = q_u - gamma * slip
    q, norm = clip_vector(trial, s)
    R = ufl.dot(q, theta * dq - gamma * v) / gamma
    if theta:
        R = -theta / gamma * ufl.dot(q_u, dq) + R
    return R, q, norm
