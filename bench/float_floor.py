"""The floor of a Python float step: bench_compose's composition fused into one function.

Every operation of one composition step of ``bench/bench_compose.py`` (two learnt skills on
one basis evaluation, obstacle steering, the 8-point potential field with its sphere query
inline, grasp maintenance on both palms, integration, phases, the palms' commands) written out
by hand in one Python function, with numpy only for the basis and the output array and
:mod:`skills.quaternion`'s scalar functions for the quaternion arithmetic (as the composer). No
composer built from separate terms can do less in Python, so its time is the floor of the
float path on this machine. The script checks that it gives the composer's numbers (to
1e-12; it exits 1 otherwise), then times both. It reads the terms' parameters from the
compiled step's packing, so it needs numba (the ``fast`` extra). With ``--json`` the last line
is ``{"fused_us": ..., "composer_us": ..., "max_diff": ...}``: mins of repeats.
"""

from __future__ import annotations

import argparse
import json
import math
import timeit
from collections.abc import Callable

import numpy as np
from bench_compose import composer

from skills import quaternion as quat
from skills.compiled import CompiledStep
from skills.composer import PalmCommands, _commands
from skills.types import Array


def fused_step(st: CompiledStep) -> Callable[[Array, float], tuple[Array, PalmCommands]]:
    """The step of the composition ``st`` packs, as one function of (state values, dt)."""
    sp = st.spaces.tolist()
    data = st.data
    (_, _, f1o), (_, _, f2o), (_, _, so), (_, _, po), (_, _, g1o), (_, _, g2o) = st.program.tolist()
    K = int(data[f1o + 1])
    tab = int(data[f1o + 3])
    table = data[tab : tab + 3 * K].reshape(3, K)
    W = np.hstack(
        (
            data[f1o + 4 : f1o + 4 + 7 * K].reshape(K, 7),
            data[f2o + 4 : f2o + 4 + 7 * K].reshape(K, 7),
        )
    )
    tau1, tau2 = data[f1o + 2], data[f2o + 2]
    w1, w2 = data[f1o], data[f2o]
    gamma, sbeta, sk_, max_angle, min_speed = data[so + 1 : so + 6].tolist()
    ox, oy, oz, reach = data[so + 7 : so + 11].tolist()
    gain, pbeta, infl, pmin, irho2 = data[po + 1 : po + 6].tolist()
    N = int(data[po + 6])
    PTS = data[po + 8 : po + 8 + 3 * N].reshape(N, 3).tolist()
    scx, scy, scz, sr = data[po + 8 + 3 * N : po + 12 + 3 * N].tolist()
    G = [data[o + 1 : o + 12].tolist() for o in (g1o, g2o)]

    def integ(
        x: list[float],
        b: int,
        a0: float,
        a1: float,
        a2: float,
        b0: float,
        b1: float,
        b2: float,
        dt: float,
        out: list[float],
    ) -> None:
        v0 = x[b + 3] + a0 * dt
        v1 = x[b + 4] + a1 * dt
        v2 = x[b + 5] + a2 * dt
        w0 = x[b + 13] + b0 * dt
        w1 = x[b + 14] + b1 * dt
        w2 = x[b + 15] + b2 * dt
        bx, by, bz, bw = x[b + 9 : b + 13]
        out += (
            x[b] + v0 * dt,
            x[b + 1] + v1 * dt,
            x[b + 2] + v2 * dt,
            v0,
            v1,
            v2,
            a0,
            a1,
            a2,
            *quat.integrate_scalar((bx, by, bz, bw), (w0, w1, w2), dt),
            w0,
            w1,
            w2,
            b0,
            b1,
            b2,
        )

    def step(values: Array, dt: float) -> tuple[Array, PalmCommands]:
        x = values.tolist()
        s = x[57]
        # object attractor
        o = sp[0]
        kp, kd = o[1], o[2]
        px, py, pz, vx, vy, vz = x[0:6]
        qx, qy, qz, qw = x[9:13]
        wx, wy, wz = x[13:16]
        e0, e1, e2 = quat.rotation_error_scalar((o[6], o[7], o[8], o[9]), (qx, qy, qz, qw))
        a0 = kp * (o[3] - px) - kd * vx
        a1 = kp * (o[4] - py) - kd * vy
        a2 = kp * (o[5] - pz) - kd * vz
        b0 = kp * e0 - kd * wx
        b1 = kp * e1 - kd * wy
        b2 = kp * e2 - kd * wz
        # two learnt forcing terms, one basis evaluation, one product
        raw = (np.exp(np.array((s * s, s, 1.0)) @ table) @ W).tolist()
        k1 = w1 * s / (max(raw[6], 1e-300) * tau1 * tau1)
        k2 = w2 * s / (max(raw[13], 1e-300) * tau2 * tau2)
        a0 += raw[0] * k1 + raw[7] * k2
        a1 += raw[1] * k1 + raw[8] * k2
        a2 += raw[2] * k1 + raw[9] * k2
        b0 += raw[3] * k1 + raw[10] * k2
        b1 += raw[4] * k1 + raw[11] * k2
        b2 += raw[5] * k1 + raw[12] * k2
        # steering
        vv = vx * vx + vy * vy + vz * vz
        if vv > min_speed * min_speed:
            dx, dy, dz = ox - px, oy - py, oz - pz
            dv = dx * vx + dy * vy + dz * vz
            dd = dx * dx + dy * dy + dz * dz
            cross = math.sqrt(max(dd * vv - dv * dv, 0.0))
            phi = math.atan2(cross, dv)
            if phi < max_angle and cross > 1e-7 * math.sqrt(dd * vv):
                cl = max(math.sqrt(dd) - reach, 0.0)
                w = gamma * phi * math.exp(-sbeta * phi - sk_ * cl * cl) / cross
                aa = w * dv
                bb = w * vv
                a0 += aa * vx - bb * dx
                a1 += aa * vy - bb * dy
                a2 += aa * vz - bb * dz
        # potential field over 8 points, sphere query inline
        m0, m1, m2, m3, m4, m5, m6, m7, m8 = quat.matrix_floats((qx, qy, qz, qw))
        fx = fy = fz = tx = ty = tz = 0.0
        power = pbeta - 1.0
        ip0 = 1.0 / infl
        for r0, r1, r2 in PTS:
            ax = m0 * r0 + m1 * r1 + m2 * r2
            ay = m3 * r0 + m4 * r1 + m5 * r2
            az = m6 * r0 + m7 * r1 + m8 * r2
            X = px + ax
            Y = py + ay
            Z = pz + az
            ux_, uy_, uz_ = X - scx, Y - scy, Z - scz
            nrm = math.sqrt(ux_ * ux_ + uy_ * uy_ + uz_ * uz_)
            d = nrm - sr
            if d >= infl:
                continue
            scl = sr / max(nrm, 1e-12)
            rx = X - (scx + ux_ * scl)
            ry = Y - (scy + uy_ * scl)
            rz = Z - (scz + uz_ * scl)
            pvx = vx + (wy * az - wz * ay)
            pvy = vy + (wz * ax - wx * az)
            pvz = vz + (wx * ay - wy * ax)
            q = -(pvx * rx + pvy * ry + pvz * rz)
            if q <= 0.0:
                continue
            ip = 1.0 / (d if d > pmin else pmin)
            g = ip - ip0
            if g <= 0.0:
                continue
            rr = rx * rx + ry * ry + rz * rz
            h = ip * (q / max(math.sqrt(rr * (pvx * pvx + pvy * pvy + pvz * pvz)), 1e-300)) ** power
            al = pbeta * g
            ka = (al + ip) * h * q / max(rr, 1e-300)
            al *= h
            ux = al * pvx + ka * rx
            uy = al * pvy + ka * ry
            uz = al * pvz + ka * rz
            fx += ux
            fy += uy
            fz += uz
            tx += ay * uz - az * uy
            ty += az * ux - ax * uz
            tz += ax * uy - ay * ux
        kk = gain * irho2
        a0 += gain * fx
        a1 += gain * fy
        a2 += gain * fz
        b0 += kk * tx
        b1 += kk * ty
        b2 += kk * tz
        out: list[float] = []
        integ(x, 0, a0, a1, a2, b0, b1, b2, dt, out)
        for arm in (0, 1):
            bb_ = 19 * (arm + 1)
            gr = G[arm]
            qa, qb, qc, qd = x[bb_ + 9 : bb_ + 13]
            e0, e1, e2 = quat.rotation_error_scalar((gr[3], gr[4], gr[5], gr[6]), (qa, qb, qc, qd))
            k_, d_, kr, dr = gr[7:11]
            integ(
                x,
                bb_,
                k_ * (gr[0] - x[bb_]) - d_ * x[bb_ + 3],
                k_ * (gr[1] - x[bb_ + 1]) - d_ * x[bb_ + 4],
                k_ * (gr[2] - x[bb_ + 2]) - d_ * x[bb_ + 5],
                kr * e0 - dr * x[bb_ + 13],
                kr * e1 - dr * x[bb_ + 14],
                kr * e2 - dr * x[bb_ + 15],
                dt,
                out,
            )
        out += (
            s * math.exp(-sp[0][11] * dt / sp[0][10]),
            x[58] * math.exp(-sp[1][11] * dt / sp[1][10]),
            x[59] * math.exp(-sp[2][11] * dt / sp[2][10]),
        )
        # commands
        px, py, pz, vx, vy, vz = out[0:6]
        x_, y_, z_, w_ = out[9:13]
        wx, wy, wz = out[13:16]
        m0, m1, m2, m3, m4, m5, m6, m7, m8 = quat.matrix_floats((x_, y_, z_, w_))
        pos: list[float] = []
        ori: list[float] = []
        tw: list[float] = []
        for bb_ in (19, 38):
            c0, c1, c2, d0, d1, d2 = out[bb_ : bb_ + 6]
            q0, q1, q2, q3, e0, e1, e2 = out[bb_ + 9 : bb_ + 16]
            l0 = m0 * c0 + m1 * c1 + m2 * c2
            l1 = m3 * c0 + m4 * c1 + m5 * c2
            l2 = m6 * c0 + m7 * c1 + m8 * c2
            pos += (px + l0, py + l1, pz + l2)
            ori += quat.multiply_scalar((x_, y_, z_, w_), (q0, q1, q2, q3))
            tw += (
                vx + wy * l2 - wz * l1 + m0 * d0 + m1 * d1 + m2 * d2,
                vy + wz * l0 - wx * l2 + m3 * d0 + m4 * d1 + m5 * d2,
                vz + wx * l1 - wy * l0 + m6 * d0 + m7 * d1 + m8 * d2,
                wx + m0 * e0 + m1 * e1 + m2 * e2,
                wy + m3 * e0 + m4 * e1 + m5 * e2,
                wz + m6 * e0 + m7 * e1 + m8 * e2,
            )
        arr = np.array((*out, *pos, *ori, *tw, vx, vy, vz, wx, wy, wz))
        return arr, _commands(arr)

    return step


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print a JSON summary last")
    args = parser.parse_args()
    c = composer()
    state = c.state
    compiled = composer(compiled=True)
    st = compiled._resolved().compiled
    assert st is not None
    step = fused_step(st)
    values = state._values
    assert values is not None
    _, cmd = step(values, 1 / 60)
    want = c.step(1 / 60, state)
    diff = max(float(np.abs(getattr(cmd, f) - getattr(want, f)).max()) for f in cmd._fields)
    n = 2000
    fused = comp = math.inf
    for _ in range(9):  # interleaved: this machine's speed drifts between runs
        fused = min(fused, timeit.timeit(lambda: step(values, 1 / 60), number=n) / n * 1e6)
        comp = min(comp, timeit.timeit(lambda: c.step(1 / 60, state), number=n) / n * 1e6)
    print(f"one Python function, every operation of the step: {fused:.1f} us (target <= 50)")
    print(f"the composer's float path: {comp:.1f} us; largest difference {diff:.1e}")
    if args.json:
        print(
            json.dumps(
                {"fused_us": round(fused, 1), "composer_us": round(comp, 1), "max_diff": diff}
            )
        )
    return 0 if diff <= 1e-12 else 1


if __name__ == "__main__":
    raise SystemExit(main())
