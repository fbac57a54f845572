#!/usr/bin/env python3
"""A straightforward numpy/scipy version of `shimmer metrics TEST REF`, for speed comparison only.

Reads the same EXR files as bench/metrics_bench (float, ZIP or uncompressed scanlines; this machine has
no Python OpenEXR bindings, so a minimal reader is included below), takes the specular luminance, and
computes the same metrics the way one would in numpy: stack the sequence into a (N, H, W) array, then
np.var, means, and scipy.signal.welch along time.  Not part of the tests.

usage: metrics_numpy_baseline.py TEST_DIR REF_DIR [--fps 60]
"""
import argparse
import glob
import json
import os
import struct
import sys
import time
import zlib

import numpy as np
import scipy.signal


def _read_attrs(f):
    attrs = {}
    while True:
        name = b""
        while (c := f.read(1)) != b"\0":
            name += c
        if not name:
            return attrs
        typ = b""
        while (c := f.read(1)) != b"\0":
            typ += c
        size = struct.unpack("<i", f.read(4))[0]
        attrs[name.decode()] = (typ.decode(), f.read(size))


def _channels(data):
    out, i = [], 0
    while data[i] != 0:
        j = data.index(b"\0", i)
        name = data[i:j].decode()
        ptype = struct.unpack("<i", data[j + 1:j + 5])[0]
        out.append((name, ptype))
        i = j + 1 + 16
    return out


def read_exr(path, wanted):
    """Returns {channel: float32 (H, W)} for the wanted channels of a single-part scanline EXR."""
    with open(path, "rb") as f:
        if struct.unpack("<i", f.read(4))[0] != 20000630:
            raise ValueError(f"{path}: not an EXR file")
        f.read(4)
        attrs = _read_attrs(f)
        chans = _channels(attrs["channels"][1])
        comp = attrs["compression"][1][0]
        x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"][1])
        w, h = x1 - x0 + 1, y1 - y0 + 1
        lines = {0: 1, 2: 1, 3: 16}[comp]
        nchunks = (h + lines - 1) // lines
        offsets = struct.unpack(f"<{nchunks}Q", f.read(8 * nchunks))
        sizes = [2 if t == 1 else 4 for _, t in chans]
        dtypes = [np.float16 if t == 1 else (np.float32 if t == 2 else np.uint32) for _, t in chans]
        out = {n: np.empty((h, w), np.float32) for n, _ in chans if n in wanted}
        for off in offsets:
            f.seek(off)
            y, size = struct.unpack("<ii", f.read(8))
            raw = f.read(size)
            n = min(lines, y1 - y + 1)
            if comp != 0 and size < n * w * sum(sizes):
                # Undo the predictor, then the even/odd byte split (OpenEXR ZIP).
                t = raw_predict(np.frombuffer(zlib.decompress(raw), np.uint8))
                half = (len(t) + 1) // 2
                b = np.empty(len(t), np.uint8)
                b[0::2] = t[:half]
                b[1::2] = t[half:]
            else:
                b = np.frombuffer(raw, np.uint8)
            if len(set(dtypes)) == 1:
                # Uniform pixel type: one reshape instead of a loop over lines and channels.
                block = np.frombuffer(b.tobytes(), dtypes[0]).reshape(n, len(chans), w)
                for k, (name, _) in enumerate(chans):
                    if name in out:
                        out[name][y - y0:y - y0 + n] = block[:, k, :]
                continue
            pos = 0
            for line in range(n):
                for (name, _), s, dt in zip(chans, sizes, dtypes):
                    if name in out:
                        out[name][y - y0 + line] = np.frombuffer(b[pos:pos + w * s].tobytes(), dt)
                    pos += w * s
        return out


def raw_predict(t):
    # OpenEXR's ZIP predictor: d[i] = d[i-1] + t[i] - 128 (mod 256), d[0] = t[0].
    d = t.copy()
    d[1:] -= np.uint8(128)  # wraps modulo 256, like the C code
    return np.cumsum(d, dtype=np.uint8)


def luminance(path):
    c = read_exr(path, {"specular.R", "specular.G", "specular.B"})
    return 0.2126 * c["specular.R"] + 0.7152 * c["specular.G"] + 0.0722 * c["specular.B"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("test")
    ap.add_argument("ref")
    ap.add_argument("--fps", type=float, default=60.0)
    a = ap.parse_args()
    start = time.perf_counter()
    tf = sorted(glob.glob(os.path.join(a.test, "*.exr")))
    rf = sorted(glob.glob(os.path.join(a.ref, "*.exr")))
    T = np.stack([luminance(p) for p in tf]).astype(np.float64)
    R = np.stack([luminance(p) for p in rf]).astype(np.float64)
    read = time.perf_counter() - start
    E = T - R
    n = T.shape[0]
    L = min(n, 64)
    f, psd = scipy.signal.welch(E, fs=a.fps, window="hann", nperseg=L, noverlap=L // 2,
                                detrend="constant", scaling="density", axis=0)
    psd = psd.reshape(psd.shape[0], -1).mean(axis=1)
    rmse_t = np.sqrt((E ** 2).mean(axis=(1, 2)))
    out = {
        "frames": n,
        "tv_test": T.var(axis=0, ddof=1).mean(),
        "tv_ref": R.var(axis=0, ddof=1).mean(),
        "tv_err": E.var(axis=0, ddof=1).mean(),
        "energy_bias": (T.sum() - R.sum()) / R.sum(),
        "temporal_diff_err": np.abs(np.diff(E, axis=0)).mean(),
        "rmse": rmse_t.mean(),
        "relmse": (E ** 2 / (R ** 2 + 0.01)).mean(axis=(1, 2)).mean(),
        "psd_peak_hz": float(f[psd.argmax()]),
    }
    total = time.perf_counter() - start
    out = {k: float(v) for k, v in out.items()}
    out.update(seconds=total, read_seconds=read, fps=n / total)
    print(json.dumps(out))


if __name__ == "__main__":
    sys.exit(main())
