#!/usr/bin/env python3
"""Would the denoiser's output make a better data term for the window solve?

A probe for issue 35 (beat path tracing + OIDN at equal time), not part of the
renderer (docs/experiments/README.md has the commands and what it measured).

It reads a finalized T-GPT shot (gdvr-farm finalize or gdvr-render output:
frame_NNNN.exr with the layers primal, dx, dy, dt, dxdt, dydt, direct, albedo,
N) and a reference sequence, and measures against the reference (per-pixel
relMSE, global relMSE, flicker, as core/image/error_metrics.h defines them):

  tgpt        the shot's own reconstruction (RGB);
  tgpt+oidn   that reconstruction denoised by OIDN, guided by albedo and normal;
  oidn(primal) the frame's primal + direct denoised by OIDN;
  guided a=α  the screened-Poisson window solve with the same sampled
              gradients (spatial, temporal, mixed) but the denoised primal as
              its data term, for several α.

The solve is written out here with scipy (CG on the normal equations), not
gdvr's solver; with the shot's own primal as the data term it reproduces the
C++ L2 result to its tolerance (mean difference 0.3 % of the mean), which the
script prints first as a check. Dropped temporal constraints are recognised
as all-zero dt (finalize zeroes them), which drops a few valid ones too.

Needs: pip install numpy scipy OpenEXR pyoidn.
Usage: denoiser_data_term.py SHOT_DIR REFERENCE_DIR FRAMES
"""
import sys

import numpy as np
import OpenEXR
import pyoidn
import scipy.sparse as sp
import scipy.sparse.linalg as spl


def load(path):
    d = {k: np.array(v.pixels, dtype=np.float32) for k, v in OpenEXR.File(path).channels().items()}
    if 'N.X' in d:
        d['N'] = np.stack([d['N.X'], d['N.Y'], d['N.Z']], -1)
    return d


def metrics(imgs, refs):
    se = sr = pp = cnt = 0.0
    for i, r in zip(imgs, refs):
        i = np.nan_to_num(i[..., :3].astype(np.float64))
        r = r[..., :3].astype(np.float64)
        se += ((i - r) ** 2).sum()
        sr += (r ** 2).sum()
        pp += ((i - r) ** 2 / (r ** 2 + 0.01)).sum()
        cnt += i.size
    fl = np.mean([(((imgs[t + 1] - refs[t + 1]) - (imgs[t] - refs[t]))[..., :3] ** 2).mean()
                  for t in range(len(imgs) - 1)])
    return pp / cnt, se / sr, fl


def denoise(color, frame):
    return pyoidn.denoise(np.ascontiguousarray(np.maximum(color, 0).astype(np.float32)),
                          np.ascontiguousarray(frame['albedo']), np.ascontiguousarray(frame['N']),
                          hdr=True, clean_aux=True, quality='high')


def forward_difference(n):
    return sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n))


def solve_window(frames, data, alpha, x0):
    """min Σ α²|I − data|² + |∇I − (dx, dy)|² + |I_t+1 − I_t − dt|² + mixed terms, per channel."""
    t_count = len(frames)
    h, w, _ = frames[0]['primal'].shape
    n = h * w
    dx_op = sp.kron(sp.identity(h), forward_difference(w))
    dy_op = sp.kron(forward_difference(h), sp.identity(w))
    rows, rhs = [], [[], [], []]

    def add(op, b, weight=None):
        if weight is not None:
            op = sp.diags(weight) @ op
            b = b * weight[:, None]
        rows.append(op)
        for c in range(3):
            rhs[c].append(b[:, c])

    def at(t, op):  # op acting on frame t of the window
        return sp.hstack([sp.csr_matrix((op.shape[0], n * t)), op, sp.csr_matrix((op.shape[0], n * (t_count - t - 1)))])

    def between(t, op):  # op(I_t+1) − op(I_t)
        z = op.shape[0]
        return sp.hstack([sp.csr_matrix((z, n * t)), -op, op, sp.csr_matrix((z, n * (t_count - t - 2)))])

    for t, f in enumerate(frames):
        add(at(t, sp.identity(n)), data[t].reshape(n, 3), alpha * np.ones(n))
        add(at(t, dx_op), f['dx'][:, :w - 1].reshape(-1, 3))
        add(at(t, dy_op), f['dy'][:h - 1].reshape(-1, 3))
        if t + 1 < t_count:
            keep = (np.abs(f['dt']).sum(-1) > 0).astype(float)
            add(between(t, sp.identity(n)), f['dt'].reshape(n, 3), keep.reshape(n))
            add(between(t, dx_op), f['dxdt'][:, :w - 1].reshape(-1, 3), keep[:, :w - 1].reshape(-1))
            add(between(t, dy_op), f['dydt'][:h - 1].reshape(-1, 3), keep[:h - 1].reshape(-1))
    a = sp.vstack(rows).tocsr()
    ata = (a.T @ a).tocsr()
    out = np.zeros((t_count * n, 3))
    for c in range(3):
        init = np.concatenate([x[..., c].reshape(-1) for x in x0])
        out[:, c], _ = spl.cg(ata, a.T @ np.concatenate(rhs[c]), x0=init, rtol=1e-5, maxiter=2000)
    return [out[t * n:(t + 1) * n].reshape(h, w, 3).astype(np.float32) for t in range(t_count)]


def main():
    shot, reference, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
    frames = [load(f'{shot}/frame_{t:04d}.exr') for t in range(count)]
    refs = [load(f'{reference}/frame_{t:04d}.exr')['RGB'] for t in range(count)]

    def report(name, imgs):
        pp, g, fl = metrics(imgs, refs)
        print(f'{name:24s} per-pixel {pp:.3e}  global {g:.3e}  flicker {fl:.3e}', flush=True)

    solved_indirect = [np.maximum(f['RGB'] - f['direct'], 0) for f in frames]
    check = solve_window(frames, [f['primal'] for f in frames], 0.2, solved_indirect)
    print('check against the C++ L2 solve: mean |difference| / mean =',
          f"{np.mean([np.abs(np.maximum(c, 0) - s).mean() for c, s in zip(check, solved_indirect)]) / np.mean([s.mean() for s in solved_indirect]):.4f}")
    report('tgpt', [f['RGB'] for f in frames])
    report('tgpt+oidn', [denoise(f['RGB'], f) for f in frames])
    guide = [denoise(f['primal'] + f['direct'], f) - f['direct'] for f in frames]
    report('oidn(primal)', [g + f['direct'] for g, f in zip(guide, frames)])
    for alpha in (0.2, 0.5, 1.0):
        solved = solve_window(frames, guide, alpha, solved_indirect)
        report(f'guided a={alpha}', [np.maximum(s, 0) + f['direct'] for s, f in zip(solved, frames)])


if __name__ == '__main__':
    main()
