#!/usr/bin/python3
"""Independent call detector on the XAV recordings vs localizer-cli's source_present.

Band energy 50-1000 Hz per frame (4096 samples, hop 2048, Hann) on one hydrophone, against
its running median over +-1.5 s (the authors' denoiser window is 3 s); a frame is a call
when energy > k x median. Compares with estimates CSVs written by `localizer-cli track`:
frames present, present outside the water column, presence statistic in present/absent
frames, the confusion matrix against the call frames, and the call intervals.

usage: /usr/bin/python3 xav_call_timeline.py DATA_DIR NAME=estimates.csv [NAME=estimates.csv ...]
(DATA_DIR: ../shared/data/xav-large-array; Debian's python3-numpy)
"""
import csv, sys, wave
import numpy as np

D = '/work/shared/data/xav-large-array'
FS, FRAME, HOP = 32000, 4096, 2048

def water_column(data_dir):
    """Surface and bottom z (z up) as localizer-cli's reader takes them from the deployment's
    files (clients/io/xav_array.h): the median over hydrophones of depth + z, and the water
    depth below it. 7.029 and -0.971 m for the XAV deployment."""
    with open(f'{data_dir}/hydrophones_config_07-HI.csv') as f:
        z = {int(r['array_channel']): float(r['z']) for r in csv.DictReader(f)}
    with open(f'{data_dir}/deployment_info.csv') as f:
        rows = list(csv.DictReader(f))
    surfaces = sorted(float(r['hydrophone_depth']) + z[int(r['audio_channel_number'])] for r in rows)
    m = len(surfaces)
    surface = surfaces[m // 2] if m % 2 else 0.5 * (surfaces[m // 2 - 1] + surfaces[m // 2])
    return surface, surface - float(rows[0]['location_water_depth'])

def read24(path):
    w = wave.open(path)
    assert w.getsampwidth() == 3 and w.getframerate() == FS
    b = np.frombuffer(w.readframes(w.getnframes()), dtype=np.uint8).reshape(-1, 3)
    v = (b[:, 0].astype(np.int32) | (b[:, 1].astype(np.int32) << 8) | (b[:, 2].astype(np.int32) << 16))
    v = np.where(v >= 1 << 23, v - (1 << 24), v)
    return v.astype(np.float64) / (1 << 23)

def band_energy(x, n_frames, lo=50.0, hi=1000.0):
    win = np.hanning(FRAME)
    f = np.fft.rfftfreq(FRAME, 1.0 / FS)
    sel = (f >= lo) & (f <= hi)
    e = np.empty(n_frames)
    for i in range(n_frames):
        X = np.fft.rfft(x[i * HOP:i * HOP + FRAME] * win)
        e[i] = np.sum(np.abs(X[sel]) ** 2)
    return e

def running_median(e, half):
    return np.array([np.median(e[max(0, i - half):i + half + 1]) for i in range(len(e))])

def intervals(mask, t):
    out, i = [], 0
    while i < len(mask):
        if mask[i]:
            j = i
            while j + 1 < len(mask) and mask[j + 1]:
                j += 1
            out.append((i, j))
            i = j + 1
        else:
            i += 1
    return out

def load(path):
    r = list(csv.DictReader(open(path)))
    return {k: np.array([float(x[k]) for x in r]) for k in r[0]}

def main():
    global D
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    D = sys.argv[1]
    surface, bottom = water_column(D)
    channel = 3  # detection_config_large_array.yaml: channel 3
    ks = [2.0, 3.0, 4.0, 8.0]
    est = {a.split('=', 1)[0]: load(a.split('=', 1)[1]) for a in sys.argv[2:]}
    n = len(next(iter(est.values()))['t_s'])
    x = read24(f'{D}/AMAR173.{channel + 1}.20190920T163858Z.wav')
    e = band_energy(x, n)
    med = running_median(e, int(round(1.5 * FS / HOP)))
    ratio = e / med
    t = next(iter(est.values()))['t_s']
    if False: np.savetxt('energy.csv', np.c_[t, e, med, ratio], delimiter=',', header='t_s,energy,median,ratio', comments='')
    print(f'frames {n}; energy ratio quantiles 10/50/90/99%: ' + ' '.join(f'{q:.2f}' for q in np.percentile(ratio, [10, 50, 90, 99])))
    for name, a in est.items():
        p = a['source_present'] > 0.5
        ini = a['initialised'] > 0.5
        z = a['z_m']
        outz = (z > surface) | (z < bottom)
        st = a['presence_statistic']; th = a['presence_threshold']
        print(f'\n== {name}: frames {n}, present {p.sum()}, absent {(~p).sum()}, initialised {ini.sum()}, ambiguous {(a["ambiguous"]>0.5).sum()}, reinitialised {(a["reinitialised"]>0.5).sum()}')
        print(f'   present outside water column: {(p & outz).sum()} (above surface {(p & (z > surface)).sum()}, below bottom {(p & (z < bottom)).sum()}); initialised outside: {(ini & outz).sum()}')
        print(f'   finite: {all(np.isfinite(v).all() for v in a.values())}; z range {z.min():.3f}..{z.max():.3f}; |xy| max {np.hypot(a["x_m"], a["y_m"]).max():.2f} m')
        for lab, m in (('present', p), ('absent', ~p)):
            if m.sum():
                q = np.percentile(st[m], [0, 10, 50, 90, 100])
                print(f'   statistic {lab}: min/p10/median/p90/max ' + ' '.join(f'{v:.2f}' for v in q))
        print(f'   threshold: min {th.min():.2f} median {np.median(th):.2f} max {th.max():.2f}; statistic/threshold median {np.median(st/th):.2f}')
        for k in ks:
            c = ratio > k
            tp = (p & c).sum(); fp = (p & ~c).sum(); fn = (~p & c).sum(); tn = (~p & ~c).sum()
            print(f'   k={k:g}: call frames {c.sum()}; confusion [present&call {tp}, present&quiet {fp}, absent&call {fn}, absent&quiet {tn}]; agreement {(tp+tn)/n:.3f}')
        # statistic vs energy ratio correlation
        print(f'   Spearman-like rank corr(statistic, energy ratio): {np.corrcoef(np.argsort(np.argsort(st)), np.argsort(np.argsort(ratio)))[0,1]:.3f}')
        if (outz & ini).any():
            idx = np.where(outz & ini)[0]
            print('   out-of-column frames (i, t, z, present): ' + ', '.join(f'({i},{t[i]:.3f},{z[i]:.2f},{int(p[i])})' for i in idx[:30]))
        if (~p).any():
            print('   absent frames: ' + ', '.join(f'({i},{t[i]:.3f})' for i in np.where(~p)[0][:40]))
    k = 4.0
    c = ratio > k
    print(f'\nCall intervals (ratio > {k:g}):')
    for i, j in intervals(c, t):
        flags = ' '.join(f'{nm}:{int((a["source_present"][i:j+1] > 0.5).sum())}/{j-i+1}' for nm, a in est.items())
        print(f'   frames {i}-{j}  t {t[i]:.3f}-{t[j]:.3f} s  peak ratio {ratio[i:j+1].max():.1f}  present {flags}')

main()
