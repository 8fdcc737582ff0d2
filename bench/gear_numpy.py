#!/usr/bin/python3
"""The gear model (doc/model.md §2) and its integrator (§5: RK4, stiffness switches split out,
backlash crossings located) in vectorised numpy, written as a competent Python user would: one
array element per realization, a Python loop over time steps, the mesh timing precomputed for all
steps at once, normals drawn in chunks; the few lanes near a flank redone one by one in Python.
Run by bench/run; see --help."""
import argparse
import json
import time

import numpy as np


class Gear:
    def __init__(self, p):
        self.__dict__.update(p)

    def acceleration(self, d, v, load, K, Q):
        """Eq. 15: Phi - Q (K g + alpha |g| v), g(d) = d - clamp(d, -b, b), the penetration
        beyond either flank (np.clip would be 4x slower on arrays this small)."""
        g = np.maximum(d - self.backlash, 0.0) + np.minimum(d + self.backlash, 0.0)
        return load - Q * (K * g + self.damping_coefficient * np.abs(g) * v)

    def friction(self, local_phase):
        return self.c0 + self.c1 * (self.x_b + self.base_radius1 * local_phase)

    def stiffness(self, local_phase):
        return np.where(local_phase < self.single_pair_angle, self.k1, self.k2)

    def schedule(self, steps):
        """Per grid step: K and f at the stage times (t_n, midpoint, t_n+1), all measured in the
        midpoint's mesh cycle, and {n: switch angle} for the steps that hold a switch."""
        n = np.arange(steps, dtype=float)
        h, P = self.time_step, self.mesh_period_angle
        a0 = self.mesh_phase + self.pinion_speed * (n * h)
        a1 = self.mesh_phase + self.pinion_speed * ((n + 1) * h)
        mid = 0.5 * (a0 + a1)
        base = np.floor(mid / P) * P
        K = self.stiffness(mid - base)
        f = np.stack([self.friction(a0 - base), self.friction(mid - base), self.friction(a1 - base)])
        # The next switch after a0; within 1e-9 of a step of a grid point it counts as on it.
        cycle = np.floor(a0 / P) * P
        nxt = cycle + np.where(a0 - cycle < self.single_pair_angle, self.single_pair_angle, P)
        tol = 1e-9 * (a1 - a0)
        split = np.nonzero((nxt > a0 + tol) & (nxt < a1 - tol))[0]
        return K, f, {int(i): (a0[i], nxt[i], a1[i]) for i in split}

    def branch_step(self, s, d, v, H, la, lb, K, qa, qm, qb):
        """One RK4 step on contact branch s (-1, 0, +1), its force law continued past the flank;
        returns the end state."""
        b, alpha = self.backlash, self.damping_coefficient

        def acc(x, y, load, q):
            if s == 0:
                return load
            g = x - s * b
            return load - q * (K * g + alpha * s * g * y)
        lm = 0.5 * (la + lb)
        a1 = acc(d, v, la, qa)
        v2 = v + 0.5 * H * a1
        a2 = acc(d + 0.5 * H * v, v2, lm, qm)
        v3 = v + 0.5 * H * a2
        a3 = acc(d + 0.5 * H * v2, v3, lm, qm)
        v4 = v + H * a3
        a4 = acc(d + H * v3, v4, lb, qb)
        return (d + H / 6 * (v + 2 * v2 + 2 * v3 + v4), v + H / 6 * (a1 + 2 * a2 + 2 * a3 + a4))

    def located(self, d, v, H, la, lb, K, qa, qm, qb):
        """One lane's segment with every crossing of |delta| = b located (doc/model.md §5): the
        first flank the step's cubic Hermite reaches (np.roots), the crossing refined by bisection
        of the RK4 step length, and a restart on the branch beyond."""
        b = self.backlash
        s = (d > b) - (d < -b)
        u0 = 0.0
        lin = lambda a, c, u: a + u * (c - a)
        for _ in range(17):
            rest = 1.0 - u0

            def step(w):
                u1 = u0 + w * rest
                qmid = qm if (u0 == 0.0 and w == 1.0) else lin(qa, qb, 0.5 * (u0 + u1))
                return self.branch_step(s, d, v, w * rest * H, lin(la, lb, u0), lin(la, lb, u1), K,
                                        lin(qa, qb, u0), qmid, lin(qa, qb, u1))
            d1, v1 = step(1.0)
            m0, m1 = rest * H * v, rest * H * v1
            cubic = [2 * (d - d1) + m0 + m1, 3 * (d1 - d) - 2 * m0 - m1, m0, d]
            flanks = [(b, 1.0, 0)] if s > 0 else [(-b, -1.0, 0)] if s < 0 else [(b, -1.0, 1), (-b, 1.0, -1)]
            first = None
            for level, side, beyond in flanks:
                shifted = cubic[:3] + [d - level]
                for r in sorted(r.real for r in np.roots(shifted) if abs(r.imag) < 1e-12 and 0 < r.real <= 1):
                    if side * np.polyval(shifted, min(1.0, r + 1e-7)) < 0:  # leaves the branch there
                        if first is None or r < first[0]:
                            first = (r, level, side, beyond)
                        break
            if first is None:
                return d1, v1
            w, level, side, beyond = first
            outside = lambda x: side * (step(x)[0] - level) < 0
            hi = min(1.0, w + 1e-6)
            if not outside(hi):
                if not outside(1.0):
                    return d1, v1  # the RK4 step itself stays on the branch
                hi = 1.0
            lo = max(0.0, w - 1e-6)
            if outside(lo):
                lo = 0.0
            for _ in range(64):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if outside(mid) else (mid, hi)
            d, v = level, step(hi)[1]
            s, u0 = beyond, u0 + hi * rest
            if u0 >= 1.0:
                return d, v
        return step(1.0)

    def rk4(self, d, v, H, la, lb, K, qa, qm, qb):
        d1, v1 = self.plain_rk4(d, v, H, la, lb, K, qa, qm, qb)
        # Lanes whose stages may have met a flank (their band, widened by the Hermite bound).
        reach = 0.25 * H * (np.abs(v) + np.abs(v1))
        x = (d, d + 0.5 * H * v, d1)
        lo, hi = np.minimum.reduce(x) - reach - H * np.abs(v), np.maximum.reduce(x) + reach + H * np.abs(v)
        b = self.backlash
        near = np.nonzero(((lo <= b) & (hi >= b)) | ((lo <= -b) & (hi >= -b)))[0]
        for i in near:
            pick = lambda a: a[i] if np.ndim(a) else a
            d1[i], v1[i] = self.located(float(d[i]), float(v[i]), H, pick(la), pick(lb), K, qa, qm, qb)
        return d1, v1

    def plain_rk4(self, d, v, H, la, lb, K, qa, qm, qb):
        lm = 0.5 * (la + lb)
        a1 = self.acceleration(d, v, la, K, qa)
        v2 = v + 0.5 * H * a1
        a2 = self.acceleration(d + 0.5 * H * v, v2, lm, K, qm)
        v3 = v + 0.5 * H * a2
        a3 = self.acceleration(d + 0.5 * H * v2, v3, lm, K, qm)
        v4 = v + H * a3
        a4 = self.acceleration(d + H * v3, v4, lb, K, qb)
        return (d + H / 6 * (v + 2 * v2 + 2 * v3 + v4),
                v + H / 6 * (a1 + 2 * a2 + 2 * a3 + a4))

    def run(self, realizations, steps, stochastic=True, every=0, seed=None, chunk=4096):
        """Integrates `realizations` paths over `steps` grid steps; returns the end (delta, v) and,
        if every > 0, the samples at steps 0, every, 2 every, ..."""
        rng = np.random.default_rng(seed)
        h, mu = self.time_step, self.mu
        sigma = self.sigma * np.sqrt(h) if stochastic else 0.0
        d = np.full(realizations, self.initial_deflection)
        v = np.full(realizations, self.initial_velocity)
        load = self.load_mean + (self.load_sd * rng.standard_normal(realizations) if stochastic else 0)
        load = load * np.ones(realizations)
        K, f, split = self.schedule(steps)
        coefficients = zip(K.tolist(), *(self.q3 + mu * f).tolist())  # Python floats: faster
        samples = [(d.copy(), v.copy())] if every else []
        for n, (K, qa, qm, qb) in enumerate(coefficients):
            if n % chunk == 0:
                z = rng.standard_normal((min(chunk, steps - n), realizations))
            load1 = load + self.drift * h + sigma * z[n % chunk]
            if n in split:  # two RK4 sub-steps, K and Q frozen at each one's midpoint
                a0, s, a1 = split[n]
                ls = load + (s - a0) / (a1 - a0) * (load1 - load)
                for lo, hi, la, lb in ((a0, s, load, ls), (s, a1, ls, load1)):
                    m = 0.5 * (lo + hi)
                    local = m - np.floor(m / self.mesh_period_angle) * self.mesh_period_angle
                    q = self.q3 + mu * self.friction(local)
                    d, v = self.rk4(d, v, (hi - lo) / (a1 - a0) * h, la, lb, self.stiffness(local), q, q, q)
            else:
                d, v = self.rk4(d, v, h, load, load1, K, qa, qm, qb)
            load = load1
            if every and (n + 1) % every == 0:
                samples.append((d.copy(), v.copy()))
        return d, v, samples


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("params", help="model parameters: the output of `gear_bench params`")
    parser.add_argument("output", help="JSON result, the same fields as gear_bench writes")
    parser.add_argument("--realizations", type=int, default=64, help="0: only the check run")
    parser.add_argument("--duration", type=float, default=0.05, help="[s]")
    parser.add_argument("--check-duration", type=float, default=0.02, help="S1 run [s]")
    parser.add_argument("--check-every", type=float, default=0.001, help="S1 sampling [s]")
    parser.add_argument("--repeat", type=int, default=1, help="timed repetitions")
    args = parser.parse_args()
    params = json.load(open(args.params))
    gear = Gear(params)
    steps = round(args.duration / gear.time_step)
    seconds, cpu_seconds, d, v = [], [], np.empty(0), np.empty(0)
    for _ in range(args.repeat if args.realizations > 0 else 0):
        start, cpu_start = time.perf_counter(), time.process_time()
        d, v, _ = gear.run(args.realizations, steps, seed=int(params["seed"]))
        seconds.append(time.perf_counter() - start)
        cpu_seconds.append(time.process_time() - cpu_start)
    every = round(args.check_every / gear.time_step)
    _, _, samples = gear.run(1, round(args.check_duration / gear.time_step), stochastic=False,
                             every=every)
    json.dump({"realizations": args.realizations, "steps": steps, "threads": 1,
               "check_every": every, "seconds": seconds, "cpu_seconds": cpu_seconds, "delta": d.tolist(),
               "velocity": v.tolist(), "check_delta": [float(s[0][0]) for s in samples],
               "check_velocity": [float(s[1][0]) for s in samples]}, open(args.output, "w"))


if __name__ == "__main__":
    main()
