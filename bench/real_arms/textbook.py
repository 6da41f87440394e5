# Textbook identification: numpy RNEA regressor from a URDF, base columns by pivoted QR on the data, ordinary least squares.
import argparse
import xml.etree.ElementTree as ET

import numpy as np
from scipy.linalg import qr

import judge

GRAVITY = 9.81
RANK_TOLERANCE = 1e-8
ZERO_COLUMN = 1e-12
INERTIAL_NAMES = ["m", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]
FRICTION_NAMES = ["fv", "fc", "fo"]


def rotation(axis, angle):
    """Rotation about a unit axis; angle may be an array (returns (..., 3, 3))."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    C = 1 - c
    return np.stack([np.stack([c + x * x * C, x * y * C - z * s, x * z * C + y * s], -1),
                     np.stack([y * x * C + z * s, c + y * y * C, y * z * C - x * s], -1),
                     np.stack([z * x * C - y * s, z * y * C + x * s, c + z * z * C], -1)], -2)


def rpy_matrix(roll, pitch, yaw):
    return rotation((0, 0, 1), yaw) @ rotation((0, 1, 0), pitch) @ rotation((1, 0, 0), roll)


def numbers(element, attribute, default):
    text = element.get(attribute) if element is not None else None
    return np.array([float(v) for v in text.split()]) if text else np.array(default, float)


def origin(element):
    """(R, p) of an element's <origin>, identity without one."""
    o = element.find("origin")
    return rpy_matrix(*numbers(o, "rpy", [0, 0, 0])), numbers(o, "xyz", [0, 0, 0])


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def link_body(link):
    """(m, c, I about c) of a link in its own axes; zeros without <inertial>."""
    inertial = link.find("inertial")
    if inertial is None:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    R, c = origin(inertial)
    m = float(inertial.find("mass").get("value"))
    i = inertial.find("inertia")
    v = {k: float(i.get(k, 0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    Ic = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]], [v["ixz"], v["iyz"], v["izz"]]])
    return m, c, R @ Ic @ R.T


def standard_vector(m, c, Ic):
    """[m, mcx, mcy, mcz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz] with the inertia about the link origin."""
    I = Ic + m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.r_[m, m * c, I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]]


class Robot:
    """The serial chain of a URDF: per movable joint its fixed transform (R, p) from the previous body's frame,
    its axis, and the standard parameters of the body it moves (fixed children merged)."""

    def __init__(self, path):
        root = ET.parse(path).getroot()
        links = {l.get("name"): l for l in root.findall("link")}
        child_joints = {}
        for j in root.findall("joint"):
            child_joints.setdefault(j.find("parent").get("link"), []).append(j)
        children = {j.find("child").get("link") for j in root.findall("joint")}
        (name,) = [n for n in links if n not in children]
        self.R, self.p, self.axes, bodies = [], [], [], []
        R_acc, p_acc = np.eye(3), np.zeros(3)
        while child_joints.get(name):
            (joint,) = child_joints[name]
            R_j, p_j = origin(joint)
            R_acc, p_acc = R_acc @ R_j, R_acc @ p_j + p_acc
            name = joint.find("child").get("link")
            m, c, Ic = link_body(links[name])
            kind = joint.get("type")
            if kind == "fixed":
                if bodies:
                    bodies[-1].append((m, R_acc @ c + p_acc, R_acc @ Ic @ R_acc.T))
                continue
            if kind not in ("revolute", "continuous"):
                raise ValueError(f"joint {joint.get('name')}: type {kind} not supported")
            axis = numbers(joint.find("axis"), "xyz", [1, 0, 0])
            self.R.append(R_acc)
            self.p.append(p_acc)
            self.axes.append(axis / np.linalg.norm(axis))
            bodies.append([(m, c, Ic)])
            R_acc, p_acc = np.eye(3), np.zeros(3)
        self.n = len(self.axes)
        self.inertial = np.concatenate([self._merge(parts) for parts in bodies])

    @staticmethod
    def _merge(parts):
        return sum(standard_vector(m, c, Ic) for m, c, Ic in parts)

    def parameter_names(self):
        return [f"{p}{i + 1}" for i in range(self.n) for p in INERTIAL_NAMES] + \
               [f"{p}{i + 1}" for i in range(self.n) for p in FRICTION_NAMES]

    def standard_parameters(self):
        """The URDF's standard parameters, no friction."""
        return np.r_[self.inertial, np.zeros(3 * self.n)]

    def regressor(self, q, qd, qdd):
        """Y of shape (samples, joints, 10 n + 3 n) with tau = Y @ pi."""
        N, n = q.shape
        w, dw, dv = np.zeros((N, 3)), np.zeros((N, 3)), np.tile([0.0, 0.0, GRAVITY], (N, 1))
        rotations, blocks = [], []
        for i in range(n):
            a = self.axes[i]
            Ri = self.R[i] @ rotation(a, q[:, i])  # (N, 3, 3): body i in body i-1
            RT = np.swapaxes(Ri, 1, 2)
            dv = np.einsum("nij,nj->ni", RT, dv + np.cross(dw, self.p[i]) + np.cross(w, np.cross(w, self.p[i])))
            w_parent = np.einsum("nij,nj->ni", RT, w)
            w = w_parent + qd[:, i:i + 1] * a
            dw = np.einsum("nij,nj->ni", RT, dw) + np.cross(w_parent, qd[:, i:i + 1] * a) + qdd[:, i:i + 1] * a
            rotations.append(Ri)
            blocks.append(self._body_block(w, dw, dv))
        Y = np.zeros((N, n, 13 * n))
        F = np.zeros((N, 6, 10 * n))
        for i in reversed(range(n)):
            F[:, :, 10 * i:10 * i + 10] += blocks[i]
            Y[:, i, :10 * n] = np.einsum("j,njk->nk", self.axes[i], F[:, 3:, :])
            if i > 0:
                Ri, p = rotations[i], self.p[i]
                f = np.einsum("nij,njk->nik", Ri, F[:, :3, :])
                moment = np.einsum("nij,njk->nik", Ri, F[:, 3:, :]) + np.einsum("ij,njk->nik", skew(p), f)
                F = np.concatenate([f, moment], axis=1)
        for i in range(n):
            Y[:, i, 10 * n + 3 * i:10 * n + 3 * i + 3] = np.column_stack([qd[:, i], np.sign(qd[:, i]), np.ones(N)])
        return Y

    @staticmethod
    def _body_block(w, dw, dv):
        """(N, 6, 10): force and moment about the body's origin, in its axes, per standard parameter."""
        def S(v):  # v x . as a matrix
            S = np.zeros((len(v), 3, 3))
            S[:, 0, 1], S[:, 0, 2], S[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
            return S - np.swapaxes(S, 1, 2)

        def L(v):  # I v = L(v) [Ixx, Ixy, Ixz, Iyy, Iyz, Izz]
            L = np.zeros((len(v), 3, 6))
            L[:, 0, 0:3] = v
            L[:, 1, [1, 3, 4]] = v
            L[:, 2, [2, 4, 5]] = v
            return L

        block = np.zeros((len(w), 6, 10))
        block[:, :3, 0] = dv
        block[:, :3, 1:4] = S(dw) + S(w) @ S(w)
        block[:, 3:, 1:4] = -S(dv)
        block[:, 3:, 4:] = L(dw) + S(w) @ L(w)
        return block


def training_rows(robot, paths, joints, cutoff=judge.CUTOFF, trim=judge.TRIM):
    """Stacked regressor rows and filtered torques of the judged joints, each run preprocessed alone."""
    Ws, ys = [], []
    for path in paths:
        t, q, qd, qdd, tau = judge.states(path, cutoff)
        tau = judge.lowpass(tau, t[1] - t[0], cutoff)
        keep = judge.inner(t, trim)
        Ws.append(robot.regressor(q[keep], qd[keep], qdd[keep])[:, joints, :].reshape(-1, 13 * robot.n))
        ys.append(tau[keep][:, joints].reshape(-1))
    return np.vstack(Ws), np.concatenate(ys)


def base_columns(W):
    """Columns of W that the data determine: columns whose norm exceeds 1e-12 of the largest, then pivoted QR of
    those columns normalised to unit norm, rank = count of |R_kk| > 1e-8 |R_00|."""
    norms = np.linalg.norm(W, axis=0)
    nonzero = np.flatnonzero(norms > ZERO_COLUMN * norms.max())
    _, R, pivots = qr(W[:, nonzero] / norms[nonzero], mode="economic", pivoting=True)
    rank = int(np.sum(np.abs(np.diag(R)) > RANK_TOLERANCE * abs(R[0, 0])))
    return np.sort(nonzero[pivots[:rank]])


def identify(robot, paths, joints):
    """(base column indices, their least-squares values)."""
    W, y = training_rows(robot, paths, joints)
    columns = base_columns(W)
    beta, *_ = np.linalg.lstsq(W[:, columns], y, rcond=None)
    return columns, beta


def predict(robot, columns, beta, q, qd, qdd):
    return robot.regressor(q, qd, qdd)[:, :, columns] @ beta


def main():
    parser = argparse.ArgumentParser(description="Textbook identification judged on a held-out run.")
    parser.add_argument("--robot", required=True)
    parser.add_argument("--train", nargs="+", required=True)
    parser.add_argument("--validate", required=True)
    parser.add_argument("--joints", help="judged joints, 1-based, e.g. 1-6 (default all)")
    args = parser.parse_args()
    robot = Robot(args.robot)
    joints = judge.parse_joints(args.joints, robot.n)
    columns, beta = identify(robot, args.train, joints)
    t, q, qd, qdd, tau = judge.states(args.validate)
    print(f"{len(columns)} base columns of {13 * robot.n}")
    print(judge.report(*judge.score(tau, predict(robot, columns, beta, q, qd, qdd), t, joints), joints))


if __name__ == "__main__":
    main()
