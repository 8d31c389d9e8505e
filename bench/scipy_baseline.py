#!/usr/bin/python3
"""The SciPy baseline the ring-down pipeline is compared with (issue 2).

What a lab script typically does, per channel and band: a 4th-order Butterworth
band-pass applied forward and backward (scipy.signal.sosfiltfilt), the analytic
signal (scipy.signal.hilbert), and one 7th-order polynomial each for the
unwrapped phase and the log-envelope over the kept span, differentiated
analytically. Acceleration is converted to displacement amplitude by dividing
the envelope by omega^2, and the decay rate is corrected by 2 d(ln omega)/dt
(method.md section 1, item 6).

Usage:
  scipy_baseline.py RECORD.csv TRUTH.csv --band 48:72 [--band LO:HI ...]
                    [--span T0:T1] [--jointlab DIR] [--repeat N]

Times the processing of every channel and band (file reading excluded, single
thread), then scores band 1 of every channel against TRUTH.csv over the span
(default: jointlab's kept span, read from DIR/summary.json) and, with
--jointlab, scores jointlab's own backbones the same way.
"""
import argparse
import json
import os
import time

import numpy as np
from scipy import signal


def read_record(path):
    """Reads jointlab's CSV test format: '# key: value' lines, a header, numbers."""
    fs = None
    with open(path) as f:
        lines = 0
        for line in f:
            if not line.startswith("#"):
                header = [h.split("[")[0].strip() for h in line.strip().split(",")]
                break
            lines += 1
            key, _, value = line[1:].partition(":")
            if key.strip() == "fs":
                fs = float(value.split()[0])
    data = np.loadtxt(path, delimiter=",", skiprows=lines + 1, ndmin=2)
    cols = {h: data[:, i] for i, h in enumerate(header)}
    if fs is None:
        fs = 1.0 / np.median(np.diff(cols["time"]))
    return fs, {h: c for h, c in cols.items() if h != "time"}


def baseline(x, fs, band, span, order=7):
    sos = signal.butter(4, band, btype="bandpass", fs=fs, output="sos")
    y = signal.sosfiltfilt(sos, x)
    z = signal.hilbert(y)
    t = np.arange(len(x)) / fs
    keep = (t >= span[0]) & (t <= span[1])
    tk = t[keep]
    tc = (tk - tk.mean()) / (tk.max() - tk.min())  # scaled for conditioning
    scale = tk.max() - tk.min()
    theta = np.polynomial.Polynomial.fit(tc, np.unwrap(np.angle(z[keep])), order)
    loga = np.polynomial.Polynomial.fit(tc, np.log(np.abs(z[keep])), order)
    wd = theta.deriv()(tc) / scale
    log_acc = loga(tc)
    # displacement amplitude = acceleration amplitude / omega^2; decay of the
    # displacement envelope = decay of acceleration + 2 d(ln omega)/dt
    sigma_acc = -loga.deriv()(tc) / scale
    dlnw = np.gradient(np.log(wd), tk)
    sigma = sigma_acc + 2 * dlnw
    wn = np.sqrt(wd**2 + sigma**2)
    amp = np.exp(log_acc) / wn**2
    return tk, amp, wn / (2 * np.pi), sigma / wn


def score(amp, f, z, truth):
    la = np.log(truth["amplitude_m"][::-1])
    ft = np.interp(np.log(amp), la, truth["frequency_hz"][::-1])
    zt = np.interp(np.log(amp), la, truth["damping_ratio"][::-1])
    ef = np.abs(f / ft - 1)
    ez = np.abs(z / zt - 1)
    return ef.max(), np.median(ef), ez.max(), np.median(ez)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("record")
    p.add_argument("truth")
    p.add_argument("--band", action="append", required=True)
    p.add_argument("--span")
    p.add_argument("--jointlab")
    p.add_argument("--repeat", type=int, default=5)
    a = p.parse_args()
    fs, chans = read_record(a.record)
    bands = [tuple(float(v) for v in b.split(":")) for b in a.band]
    truth = np.genfromtxt(a.truth, delimiter=",", names=True)

    spans = {}
    if a.jointlab:
        summary = json.load(open(os.path.join(a.jointlab, "summary.json")))
        for out in summary["files"][0]["outputs"]:
            if out["band"] == 1 and out.get("file"):
                spans[out["channel"]] = (out["span_start_s"], out["span_end_s"])
    if a.span:
        s0, s1 = (float(v) for v in a.span.split(":"))
        spans = {n: (s0, s1) for n in chans}
    default_span = (0.2, 2.5)

    times = []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        for n, x in chans.items():
            for b in bands:
                baseline(x, fs, b, spans.get(n, default_span))
        times.append(time.perf_counter() - t0)
    print(f"scipy baseline: {1e3 * np.median(times):.1f} ms per record "
          f"({len(chans)} channels x {len(bands)} bands, median of {a.repeat})")

    rows = []
    for n, x in chans.items():
        tk, amp, f, z = baseline(x, fs, bands[0], spans.get(n, default_span))
        rows.append(score(amp, f, z, truth))
    r = np.array(rows)
    print("scipy baseline band 1: max f err %.2e, median f err %.2e, max zeta err %.4f, "
          "median zeta err %.4f (worst channel)" % (r[:, 0].max(), r[:, 1].max(), r[:, 2].max(),
                                                     r[:, 3].max()))
    if a.jointlab:
        rows = []
        stem = os.path.splitext(os.path.basename(a.record))[0]
        for n in chans:
            path = os.path.join(a.jointlab, f"{stem}.{n}.band1.csv")
            if not os.path.exists(path):
                continue
            d = np.genfromtxt(path, delimiter=",", names=True)
            rows.append(score(d["displacement_m"], d["frequency_hz"], d["damping_ratio"], truth))
        r = np.array(rows).reshape(-1, 4)
        print("jointlab band 1:       max f err %.2e, median f err %.2e, max zeta err %.4f, "
              "median zeta err %.4f (worst channel)" % (r[:, 0].max(), r[:, 1].max(),
                                                       r[:, 2].max(), r[:, 3].max()))


if __name__ == "__main__":
    main()
