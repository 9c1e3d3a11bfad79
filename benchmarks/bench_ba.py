"""Timing of pose-only optimisation and local bundle adjustment, side by side with a peer.

    .venv/bin/python benchmarks/bench_ba.py [--repeats 9] [--peer-repeats 1] [--seed 0]

Synthetic KITTI-like street (KITTI 0001 stereo rig, points 3-60 m, 1 px noise scaled by an
ORB octave, stereo under 40 m, mono beyond):

* optimize_pose: ~600 observations, 20 % gross outliers, start 0.3 m / 3 deg off.
* bundle_adjust: 10 keyframes (2 fixed), ~3000 points, ~15000 observations, 5 % outliers,
  poses perturbed by 10 cm / 1 deg, points by 20 cm; ours twice: the default (the built-in
  dense-Schur Levenberg-Marquardt) and the same problem through Ceres' DENSE_SCHUR.

The peer is scipy.optimize.least_squares, run in the same process on the same data (pyceres
is not installable from the package index here): trf with a Huber loss for the pose; for the
BA trf + lsmr with a sparse finite-difference Jacobian and a soft-L1 loss (its Huber loss
stalls on this problem). Prints median wall times, the ratio peer / twistslam, and the
accuracy of both (so that a fast but wrong answer shows).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix
from scipy.spatial.transform import Rotation

from twistslam import geometry as g
from twistslam import optim

P2 = np.array([[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791],
               [0, 0, 1, 0.002745884]])
P3 = np.array([[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936],
               [0, 0, 1, 0.002729905]])


def street_pose(k: int) -> np.ndarray:
    T_w_c = np.eye(4)
    T_w_c[:3, :3] = Rotation.from_rotvec([0, 0.01 * k, 0]).as_matrix()
    T_w_c[:3, 3] = [0.3 * np.sin(0.2 * k), 0.02 * k, 1.5 * k]
    return np.linalg.inv(T_w_c)


def perturb(T, t, angle, rng):
    a, b = rng.normal(size=3), rng.normal(size=3)
    xi = np.concatenate([a / np.linalg.norm(a) * t, b / np.linalg.norm(b) * angle])
    return g.se3_exp(xi) @ T


def street_points(rng, n, z_min, z_max):
    z = rng.uniform(z_min, z_max, n)
    side = np.where(rng.uniform(size=n) < 0.5, -1.0, 1.0)
    x = np.where(rng.uniform(size=n) < 0.7, side * rng.uniform(6, 14, n), rng.uniform(-6, 6, n))
    return np.stack([x, rng.uniform(-4, 1.6, n), z], axis=1)


def observe(cam, T_c_w, X_w, rng):
    X_c = g.transform_points(T_c_w, X_w)
    uv = cam.project(X_c)
    ur = cam.project(X_c, right=True)[:, 0]
    depth = X_c[:, 2] + cam.t_left[2]
    vis = (depth > 3) & (depth < 60) & (uv[:, 0] > 5) & (uv[:, 0] < 1236) & (uv[:, 1] > 5) & \
        (uv[:, 1] < 369)
    sigma = 1.2 ** rng.integers(0, 4, len(X_w))
    uv = uv + sigma[:, None] * rng.normal(size=uv.shape)
    ur = np.where(X_c[:, 2] < 40, ur + sigma * rng.normal(size=len(ur)), -1.0)
    return uv, ur, 1.0 / sigma**2, vis


def centre_err(A, B):
    return float(np.linalg.norm(np.linalg.inv(A)[:3, 3] - np.linalg.inv(B)[:3, 3]))


# ---------------------------------------------------------------------------- residuals (peer)
def stereo_residuals(cam, R, t, X, uv, ur, sqrt_info):
    """(E, 3) whitened residuals; the third is 0 for mono observations."""
    X_c = np.einsum("eij,ej->ei", R, X) + t
    Xl, Xr = X_c + cam.t_left, X_c + cam.t_right
    u = cam.fx * Xl[:, 0] / Xl[:, 2] + cam.cx
    v = cam.fy * Xl[:, 1] / Xl[:, 2] + cam.cy
    u_r = cam.fx * Xr[:, 0] / Xr[:, 2] + cam.cx
    r = np.stack([u - uv[:, 0], v - uv[:, 1], np.where(ur >= 0, u_r - ur, 0.0)], axis=1)
    return r * sqrt_info[:, None]


def compose(x6, T0):
    """T = exp-like update of T0 by x6 = [t increment, rotation vector], left-multiplied."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(x6[3:]).as_matrix()
    T[:3, 3] = x6[:3]
    return T @ T0


# ---------------------------------------------------------------------------- pose benchmark
def pose_scene(cam, rng, n=600, outliers=0.2):
    T_true = street_pose(7)
    X_w = g.transform_points(np.linalg.inv(T_true), street_points(rng, 4 * n, 3, 60))
    uv, ur, info, vis = observe(cam, T_true, X_w, rng)
    X_w, uv, ur, info = X_w[vis][:n], uv[vis][:n], ur[vis][:n], info[vis][:n]
    out = rng.uniform(size=n) < outliers
    uv[out] = np.stack([rng.uniform(5, 1236, out.sum()), rng.uniform(5, 369, out.sum())], 1)
    ur[out] = np.where(ur[out] >= 0, uv[out, 0] - rng.uniform(1, 80, out.sum()), -1.0)
    T0 = perturb(T_true, 0.3, np.radians(3), rng)
    return T_true, T0, X_w, uv, ur, info


def pose_peer(cam, T0, X_w, uv, ur, info):
    s = np.sqrt(info)

    def fun(x):
        T = compose(x, T0)
        R = np.broadcast_to(T[:3, :3], (len(X_w), 3, 3))
        return stereo_residuals(cam, R, T[:3, 3], X_w, uv, ur, s).ravel()

    sol = least_squares(fun, np.zeros(6), method="trf", loss="huber", f_scale=2.0)
    return compose(sol.x, T0)


# ---------------------------------------------------------------------------- BA benchmark
def ba_scene(cam, rng, K=10, n_fixed=2, M=3000, outliers=0.05):
    poses = np.stack([street_pose(k) for k in range(K)])
    X = street_points(rng, 4 * M, 3, 1.5 * K + 45)
    kf, pt, uvs, urs, infos = [], [], [], [], []
    for k in range(K):
        uv, ur, info, vis = observe(cam, poses[k], X, rng)
        idx = np.nonzero(vis)[0]
        kf.append(np.full(len(idx), k)), pt.append(idx)
        uvs.append(uv[idx]), urs.append(ur[idx]), infos.append(info[idx])
    kf, pt = np.concatenate(kf), np.concatenate(pt)
    uv, ur, info = np.concatenate(uvs), np.concatenate(urs), np.concatenate(infos)
    # at most 5 observations per point (consecutive keyframes), ~15000 in all
    order = np.lexsort((kf, pt))
    kf, pt, uv, ur, info = kf[order], pt[order], uv[order], ur[order], info[order]
    first = np.searchsorted(pt, pt)
    rank = np.arange(len(pt)) - first
    count = np.bincount(pt, minlength=len(X))
    start = rng.integers(0, np.maximum(count - 5, 0) + 1)[pt]
    sel = (rank >= start) & (rank < start + 5)
    kf, pt, uv, ur, info = kf[sel], pt[sel], uv[sel], ur[sel], info[sel]
    keep = np.nonzero(np.bincount(pt, minlength=len(X)) >= 2)[0][:M]
    remap = -np.ones(len(X), dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    sel = remap[pt] >= 0
    kf, pt, uv, ur, info = kf[sel], remap[pt[sel]], uv[sel], ur[sel], info[sel]
    out = rng.uniform(size=len(kf)) < outliers
    ang, d = rng.uniform(0, 2 * np.pi, out.sum()), rng.uniform(15, 60, out.sum())
    uv[out] += d[:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    ur[out] = np.where(ur[out] >= 0, uv[out, 0] - rng.uniform(1, 60, out.sum()), -1.0)
    fixed = np.arange(K) < n_fixed
    poses0 = np.stack([p if f else perturb(p, 0.1, np.radians(1), rng)
                       for p, f in zip(poses, fixed)])
    X0 = X[keep] + 0.2 / np.sqrt(3) * rng.normal(size=(len(keep), 3))
    return dict(poses=poses, poses0=poses0, X0=X0, fixed=fixed, kf=kf, pt=pt, uv=uv, ur=ur,
                info=info)


def ba_peer(cam, s, max_nfev):
    free = np.nonzero(~s["fixed"])[0]
    slot = -np.ones(len(s["fixed"]), dtype=np.int64)
    slot[free] = np.arange(len(free))
    F, M, E = len(free), len(s["X0"]), len(s["kf"])
    sq = np.sqrt(s["info"])
    kf, pt = s["kf"], s["pt"]

    def unpack(x):
        poses = s["poses0"].copy()
        for i, k in enumerate(free):
            poses[k] = compose(x[6 * i:6 * i + 6], s["poses0"][k])
        return poses, x[6 * F:].reshape(M, 3)

    def fun(x):
        poses, X = unpack(x)
        return stereo_residuals(cam, poses[kf, :3, :3], poses[kf, :3, 3], X[pt], s["uv"],
                                s["ur"], sq).ravel()

    A = lil_matrix((3 * E, 6 * F + 3 * M), dtype=np.int8)
    rows = np.arange(E)
    for c in range(3):
        for j in range(3):
            A[3 * rows + c, 6 * F + 3 * pt + j] = 1
        has = slot[kf] >= 0
        for j in range(6):
            A[3 * rows[has] + c, 6 * slot[kf[has]] + j] = 1
    x0 = np.concatenate([np.zeros(6 * F), s["X0"].ravel()])
    sol = least_squares(fun, x0, jac_sparsity=A, method="trf", loss="soft_l1", f_scale=2.0,
                        tr_solver="lsmr", max_nfev=max_nfev)
    return unpack(sol.x)


def median_ms(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(1e3 * (time.perf_counter() - t0))
    return float(np.median(times)), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--peer-repeats", type=int, default=1)
    parser.add_argument("--peer-max-nfev", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    cam = g.StereoCamera.from_kitti(P2, P3, 1242, 375)
    print(f"peer: scipy {scipy.__version__} least_squares (pyceres not available)")

    T_true, T0, X_w, uv, ur, info = pose_scene(cam, rng)
    ours_ms, r = median_ms(lambda: optim.optimize_pose(T0, X_w, uv, ur, info, cam),
                           20 * args.repeats)
    peer_ms, T_peer = median_ms(lambda: pose_peer(cam, T0, X_w, uv, ur, info), args.peer_repeats)
    print(f"\noptimize_pose, {len(X_w)} observations (20 % outliers)")
    print(f"  twistslam  {ours_ms:9.3f} ms   centre error {100 * centre_err(r['T_c_w'], T_true):.2f} cm"
          f"   inliers {r['num_inliers']}")
    print(f"  scipy      {peer_ms:9.3f} ms   centre error {100 * centre_err(T_peer, T_true):.2f} cm")
    print(f"  ratio peer / twistslam: {peer_ms / ours_ms:.1f}x")

    s = ba_scene(cam, rng)
    print(f"\nbundle_adjust, {len(s['poses'])} keyframes (2 fixed), {len(s['X0'])} points, "
          f"{len(s['kf'])} observations ({100 * np.mean(s['ur'] >= 0):.0f} % stereo)")

    err0 = np.mean([centre_err(s["poses0"][k], s["poses"][k]) for k in range(2, 10)])

    def run_ours(label, solver):
        def ours():
            return optim.bundle_adjust(s["poses0"], s["fixed"], s["X0"], None, s["kf"], s["pt"],
                                       s["uv"], s["ur"], s["info"], cam, linear_solver=solver)

        ours()  # warm-up
        solve_ms = []

        def timed():
            r = ours()
            solve_ms.append(r["solve_ms"])
            return r

        ms, r = median_ms(timed, args.repeats)
        err = np.mean([centre_err(r["poses_c_w"][k], s["poses"][k]) for k in range(2, 10)])
        print(f"  {label} {ms:9.1f} ms (C++ solve_ms median {np.median(solve_ms):.1f}, "
              f"min {np.min(solve_ms):.1f})   {r['iterations']} iterations, rmse "
              f"{r['initial_rmse_px']:.2f} -> {r['final_rmse_px']:.2f} px, mean pose error "
              f"{100 * err0:.1f} -> {100 * err:.2f} cm")
        return ms, r

    # the default: the built-in dense-Schur Levenberg-Marquardt; beside it the same problem
    # through Ceres' DENSE_SCHUR (the same steps, optim/schur_lm.hpp)
    ours_ms, r = run_ours("twistslam ", "auto")
    ceres_ms, r_ceres = run_ours("  via Ceres", "dense_schur")
    print(f"  (built-in vs Ceres: {ceres_ms / ours_ms:.1f}x faster, poses within "
          f"{np.max(np.abs(np.asarray(r['poses_c_w']) - np.asarray(r_ceres['poses_c_w']))):.1e})")
    peer_ms, (poses_p, _) = median_ms(lambda: ba_peer(cam, s, args.peer_max_nfev),
                                      args.peer_repeats)
    err_p = np.mean([centre_err(poses_p[k], s["poses"][k]) for k in range(2, 10)])
    print(f"  scipy      {peer_ms:9.1f} ms (max_nfev {args.peer_max_nfev})   mean pose error "
          f"{100 * err_p:.2f} cm")
    print(f"  ratio peer / twistslam: {peer_ms / ours_ms:.1f}x")


if __name__ == "__main__":
    main()

