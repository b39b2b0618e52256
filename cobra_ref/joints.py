"""Joint models: jcalc(joint_type, q_i, qd_i) -> (X_J, S, c_J).

Implements: [RBDA] ch. 4, Table 4.1 (revolute joints) and the free joint in MuJoCo's
coordinates (see cobra_ref.model).

* ``X_J`` : (6, 6)   joint transform, predecessor -> successor (body) coordinates
* ``S``   : (6, n_i) motion subspace in body coordinates: v_J = S @ qd_i
* ``c_J`` : (6,)     velocity-product term S-dot qd_i (zero for revolute joints)
"""

from __future__ import annotations

import numpy as np

from .quaternion import quat_to_rot
from .spatial import plux, rotx, roty, rotz, skew

_REVOLUTE = {"Rx": (rotx, 0), "Ry": (roty, 1), "Rz": (rotz, 2)}


def jcalc(joint_type: str, q_i: np.ndarray, qd_i: np.ndarray):
    """Joint transform, motion subspace and velocity-product term of one joint.

    Implements: [RBDA] Table 4.1 for 'Rx', 'Ry', 'Rz'; for 'free' (MuJoCo's free joint)::

        X_J = plux(R^T, p)                       # world -> body, R = R(quat), p = position
        S   = [ 0    1 ]   (qd_i = [v_world; w_body])
              [ R^T  0 ]
        c_J = [ 0 ; -w_body x (R^T v_world) ]     # d/dt(R^T) = -[w_body]x R^T

    Notes
    -----
    The free joint's spatial acceleration in body coordinates is
    a = [w_body'; R^T p'' - w_body x R^T p'] = S qdd_i + c_J (derived from the definition of the
    spatial acceleration, [RBDA] sec. 2.11).
    """
    if joint_type == "free":
        p, R = q_i[:3], quat_to_rot(q_i[3:7])
        S = np.zeros((6, 6))
        S[:3, 3:] = np.eye(3)
        S[3:, :3] = R.T
        c_J = np.zeros(6)
        c_J[3:] = -skew(qd_i[3:]) @ (R.T @ qd_i[:3])
        return plux(R.T, p), S, c_J
    rot, axis = _REVOLUTE[joint_type]
    S = np.zeros((6, 1))
    S[axis, 0] = 1.0
    return rot(q_i[0]), S, np.zeros(6)
