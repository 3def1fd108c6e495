"""Why a conservative sparsification (H~ <= H) needs what a constant-time SEIF does not have.

On random positive definite information matrices shaped like a SEIF's (a robot linked only
to its active landmarks Y+ and Y0, the rest of the map beyond), with H = S + Phi split into
the map's marginal information S (no robot rows) and the robot's conditional factor
Phi = [I -K]^T H_xx [I -K] (x = K y_A + w), three ways to cut the robot-Y0 link:

(a) keep S, replace the conditional by the exact p(x | Y+): the covariance difference has a
    zero map block and a nonzero robot-map block, so it is never >= 0 (not conservative);
(b) keep S, replace Phi by [I -K]^T M [I -K] with 0 <= M <= H_xx and M K0 = 0: sparse,
    0 <= H~ <= H always, but the robot keeps information in 3 - rank(K0) = 1 direction;
(c) also take information from Y0 ((a-b)^T W (a-b) >= (1-e) a^T W a - (1/e-1) b^T W b):
    <= H, but positive semi-definite only when Y0's marginal information exceeds what is
    taken - a global quantity.

Run:  /usr/bin/python3 scripts/figures/conservative_sparsification.py [--trials 200]
"""
import argparse

import numpy as np


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trials", type=int, default=200)
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()
    rng = np.random.default_rng(a.seed)
    n = 3 + 2 * 8  # robot; Y+ = two landmarks (rows 3-6), Y0 = one (7-8); five more beyond
    x, A, yp, y0 = slice(0, 3), slice(3, 9), slice(3, 7), slice(7, 9)
    not_conservative = sparse_and_safe = indefinite = 0
    for _ in range(a.trials):
        G = rng.normal(size=(n, n))
        H = G @ G.T
        H[x, 9:] = 0
        H[9:, x] = 0
        H += np.eye(n) * (0.1 - min(0.0, np.linalg.eigvalsh(H).min()))
        W = H[x, x]
        K = -np.linalg.solve(W, H[x, A])
        J = np.zeros((3, n))
        J[:, x] = np.eye(3)
        J[:, A] = -K
        S = H - J.T @ W @ J
        Sigma = np.linalg.inv(H)
        # (a)
        Ac = Sigma[x, yp] @ np.linalg.inv(Sigma[yp, yp])
        Jc = np.zeros((3, n))
        Jc[:, x] = np.eye(3)
        Jc[:, yp] = -Ac
        Ha = S + Jc.T @ np.linalg.inv(Sigma[x, x] - Ac @ Sigma[yp, x]) @ Jc
        not_conservative += np.linalg.eigvalsh(np.linalg.inv(Ha) - Sigma).min() < -1e-9
        # (b)
        K0 = K[:, 4:6]
        Q, _ = np.linalg.qr(W @ K0, mode="complete")
        N0 = Q[:, 2:]
        M = W @ N0 @ np.linalg.inv(N0.T @ W @ N0) @ N0.T @ W
        Hb = S + J.T @ M @ J
        sparse_and_safe += (np.abs(Hb[x, y0]).max() < 1e-9 and np.linalg.eigvalsh(H - Hb).min() > -1e-9
                            and np.linalg.eigvalsh(Hb).min() > -1e-9)
        # (c), e = 1/2
        e = 0.5
        ra = np.zeros((3, n))
        ra[:, x] = np.eye(3)
        ra[:, yp] = -K[:, 0:4]
        rb = np.zeros((3, n))
        rb[:, y0] = K0
        Hc = S + (1 - e) * ra.T @ W @ ra - (1 / e - 1) * rb.T @ W @ rb
        indefinite += np.linalg.eigvalsh(Hc).min() < -1e-9
    t = a.trials
    print(f"(a) keep the map, exact p(x | Y+): not conservative in {not_conservative} / {t}")
    print(f"(b) keep the map, M K0 = 0: sparse, 0 <= H~ <= H in {sparse_and_safe} / {t}; "
          f"the robot keeps information in {np.linalg.matrix_rank(M)} of 3 directions")
    print(f"(c) take from Y0 too (e = 1/2): H~ indefinite in {indefinite} / {t}")


if __name__ == "__main__":
    main()
