"""Compiled inner loops of the ISO 532-1 loudness stage (numba). Callers reach them through
:mod:`.compiled`, which loads them built ahead of time, without importing numba.

Why compiled: the nonlinear decay and the slope construction are sequential, state-dependent
recursions (a branch per band and per 0.5 ms sample, 24 virtual sub-steps each) that numpy cannot
vectorise, and scipy's ``sosfilt`` runs a float64 biquad at about 5.9 ns per sample on the
benchmark machine, which alone puts the 28-band ISO filter bank (with its smoothers, via
``lfilter``) at ~0.03 s per second of audio, three times the whole budget. Figures before/after
are recorded in :mod:`autohaptics.bench.audio`.

Every kernel is a plain loop over numpy arrays: with ``NUMBA_DISABLE_JIT=1`` the same source runs
as pure Python (the slow reference path). Streaming kernels never allocate their state: the
caller passes copies of the state arrays, the kernel updates them in place and the caller
returns them. Layouts are band-major ``[shape=(n_bands, n_samples)]``: each band's recursion walks
contiguous memory.

Digital silence: over exact zeros a recursive state rings down geometrically, through the subnormal
doubles (below 2.2e-308), which cost ~100 cycles an operation on Intel CPUs. Every recursive state
is therefore set to exactly 0 once it falls below :data:`FLUSH_FLOOR`, checked at each output sample
(every 1-24 input samples, a position fixed by the global sample index, so chunked still equals
whole); from there silence keeps it 0. Between two checks a free state falls by less than a factor
~100 (the fastest poles: radius 0.5 in the decimators, checked every 2-3 samples; 0.85 in the band
filters, every <= 24), so from above the floor it never nears 1e-308: no subnormal enters the loops
but by a chance cancellation.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_JIT = dict(cache=True, nogil=True)

# Recursive states below this magnitude become exactly 0 (Pa for filter states, Pa^2 for the
# smoothers, sone/Bark and sone for the decay and the temporal weighting). 1e-100 Pa is ~1900 dB
# under ISO 532-1's threshold in quiet, a band mean square of 1e-200 Pa^2 adds nothing to its
# 1e-12 Pa^2 TINY_INTENSITY, and a loudness of 1e-100 sone is 0 in the float32 outputs; its square
# (1e-200) stays a normal double, so a squared state (band energy, low-pass energy) is flushed or
# normal too.
FLUSH_FLOOR = 1e-100


@numba.njit(**_JIT)
def _flush(v):
    # v, or exactly 0 where |v| < FLUSH_FLOOR (NaN passes through)
    return 0.0 if abs(v) < FLUSH_FLOOR else v


@numba.njit(**_JIT)
def _flush_sections(zi):
    # _flush on every state of a cascade, zi [shape=(n_sections, 2)] (in place)
    for s in range(zi.shape[0]):
        zi[s, 0] = _flush(zi[s, 0])
        zi[s, 1] = _flush(zi[s, 1])


@numba.njit(**_JIT)
def bank_square_smooth(x, sos, gain, smooth_a, zi_sos, zi_smooth, first_out, step, out):
    """Band-pass, square and smooth ``x`` for every band of one filter-bank group.

    x : float64 [shape=(n,)], Pa, at the group's rate.
    sos : float64 [shape=(n_bands, 3, 6)], three second-order sections (b0 b1 b2 1 a1 a2) per band.
    gain : float64 [shape=(n_bands,)], applied after the sections.
    smooth_a : float64 [shape=(n_bands,)], pole of the three cascaded first-order smoothers.
    zi_sos : float64 [shape=(n_bands, 3, 2)], transposed direct form II state (in/out).
    zi_smooth : float64 [shape=(n_bands, 3)], smoother state (in/out).
    first_out, step : the smoothed mean square is written for local samples
        first_out, first_out + step, ... into ``out[b, k]``; the states are flushed there.
    out : float64 [shape=(n_bands, n_out)], Pa^2.
    """
    n = x.shape[0]
    n_bands = sos.shape[0]
    for b in range(n_bands):
        a = smooth_a[b]
        c = 1.0 - a
        g = gain[b]
        y1 = zi_smooth[b, 0]
        y2 = zi_smooth[b, 1]
        y3 = zi_smooth[b, 2]
        k = 0
        nxt = first_out
        b00 = sos[b, 0, 0]; b01 = sos[b, 0, 1]; b02 = sos[b, 0, 2]; a01 = sos[b, 0, 4]; a02 = sos[b, 0, 5]
        b10 = sos[b, 1, 0]; b11 = sos[b, 1, 1]; b12 = sos[b, 1, 2]; a11 = sos[b, 1, 4]; a12 = sos[b, 1, 5]
        b20 = sos[b, 2, 0]; b21 = sos[b, 2, 1]; b22 = sos[b, 2, 2]; a21 = sos[b, 2, 4]; a22 = sos[b, 2, 5]
        s01 = zi_sos[b, 0, 0]; s02 = zi_sos[b, 0, 1]
        s11 = zi_sos[b, 1, 0]; s12 = zi_sos[b, 1, 1]
        s21 = zi_sos[b, 2, 0]; s22 = zi_sos[b, 2, 1]
        for i in range(n):
            v = x[i]
            w = b00 * v + s01
            s01 = b01 * v - a01 * w + s02
            s02 = b02 * v - a02 * w
            v = b10 * w + s11
            s11 = b11 * w - a11 * v + s12
            s12 = b12 * w - a12 * v
            w = b20 * v + s21
            s21 = b21 * v - a21 * w + s22
            s22 = b22 * v - a22 * w
            w = g * w
            e = w * w
            y1 = c * e + a * y1
            y2 = c * y1 + a * y2
            y3 = c * y2 + a * y3
            if i == nxt:
                s01 = _flush(s01); s02 = _flush(s02); s11 = _flush(s11)
                s12 = _flush(s12); s21 = _flush(s21); s22 = _flush(s22)
                y1 = _flush(y1); y2 = _flush(y2); y3 = _flush(y3)
                out[b, k] = y3
                k += 1
                nxt += step
        zi_sos[b, 0, 0] = s01; zi_sos[b, 0, 1] = s02
        zi_sos[b, 1, 0] = s11; zi_sos[b, 1, 1] = s12
        zi_sos[b, 2, 0] = s21; zi_sos[b, 2, 1] = s22
        zi_smooth[b, 0] = y1
        zi_smooth[b, 1] = y2
        zi_smooth[b, 2] = y3


@numba.njit(**_JIT)
def sos_decimate(x, sos, zi, first_out, step, out):
    """Low-pass ``x`` with cascaded sections and keep local samples first_out, first_out + step, ...

    x : float64 [shape=(n,)]; sos : [shape=(n_sections, 6)]; zi : [shape=(n_sections, 2)] (in/out),
    flushed at each kept sample; out : float64 [shape=(n_out,)].
    """
    n = x.shape[0]
    n_sec = sos.shape[0]
    k = 0
    nxt = first_out
    for i in range(n):
        v = x[i]
        for s in range(n_sec):
            w = sos[s, 0] * v + zi[s, 0]
            zi[s, 0] = sos[s, 1] * v - sos[s, 4] * w + zi[s, 1]
            zi[s, 1] = sos[s, 2] * v - sos[s, 5] * w
            v = w
        if i == nxt:
            _flush_sections(zi)
            out[k] = v
            k += 1
            nxt += step


@numba.njit(**_JIT)
def core_loudness(ms, tiny, i_ref, i_max_low, lf_thresholds, lf_factors, edges, high_offset, band_factor, i_ltq,
                  dcb_factor, mp1, out):
    """Core loudness of 21 critical bands from 28 band mean squares, in the intensity domain.

    ms : float64 [shape=(28, m)], Pa^2. Levels are never formed: every dB comparison and dB sum
    of ISO 532-1 A.3-A.7 is done on intensities (I / I_ref), which is exact and avoids 48 logs
    and powers per 0.5 ms.
    i_max_low : intensity ratio of 120 dB; the 11 bands <= 250 Hz are clamped to it.
    lf_thresholds : [shape=(7, 11)] 10**((RAP - DLL) / 10); lf_factors : [shape=(8, 11)] 10**(DLL / 10).
    edges : int64 [shape=(4,)] third-octave bands merged into critical bands 0, 1, 2;
    critical band j >= 3 reads third-octave band j + high_offset.
    band_factor : [shape=(20,)] 10**((DDF? - A0) / 10); i_ltq : 10**(LTQ / 10);
    dcb_factor : 10**(-DCB / 10) / i_ltq; mp1 : 0.0635 * 10**(0.025 LTQ).
    out : float64 [shape=(21, m)], sone/Bark.
    """
    m = ms.shape[1]
    n_low = lf_thresholds.shape[1]
    n_thr = lf_thresholds.shape[0]
    n_core = i_ltq.shape[0]
    for t in range(m):
        cb0 = 0.0
        cb1 = 0.0
        cb2 = 0.0
        for i in range(n_low):
            x = (ms[i, t] + tiny) / i_ref
            if x > i_max_low:
                x = i_max_low
            k = 0
            while k < n_thr and x > lf_thresholds[k, i]:
                k += 1
            x *= lf_factors[k, i]
            if i < edges[1]:
                cb0 += x
            elif i < edges[2]:
                cb1 += x
            else:
                cb2 += x
        for j in range(n_core):
            if j == 0:
                x = cb0
            elif j == 1:
                x = cb1
            elif j == 2:
                x = cb2
            else:
                x = (ms[j + high_offset, t] + tiny) / i_ref
            x *= band_factor[j]
            v = 0.0
            if x > i_ltq[j]:
                v = mp1[j] * (math.sqrt(math.sqrt(0.75 + 0.25 * x * dcb_factor[j])) - 1.0)
                if v < 0.0:
                    v = 0.0
            out[j, t] = v
        c = 0.4 + 0.32 * out[0, t] ** 0.2
        if c < 1.0:
            out[0, t] *= c
        for j in range(n_core, out.shape[0]):
            out[j, t] = 0.0


@numba.njit(**_JIT)
def _nl_step(ui, uo_last, u2_last, b0, b1, b2, b3, b4, b5, tol):
    # One step of the decay network of ISO 532-1 clause 6.5 (two capacitors, three cases).
    if ui < uo_last:
        if uo_last > u2_last:
            u2 = uo_last * b0 - u2_last * b1
            uo = uo_last * b2 - u2_last * b3
            if ui > uo:
                uo = ui
            if u2 > uo:
                u2 = uo
        else:
            uo = uo_last * b4
            if ui > uo:
                uo = ui
            u2 = uo
    else:
        uo = ui
        if abs(ui - uo_last) < tol and uo <= u2_last:
            u2 = ui
        else:
            u2 = (u2_last - ui) * b5 + ui
    return uo, u2


@numba.njit(**_JIT)
def nonlinear_decay(core, coef, n_iter, tol, uo_last, u2_last, prev_in, started, out):
    """Nonlinear temporal decay of the core loudness, band by band.

    core : float64 [shape=(n_bands, n)], sone/Bark at 2 kHz.
    coef : float64 [shape=(6,)], the network constants B0..B5 for the sub-step length.
    n_iter : sub-steps per sample (the input is interpolated linearly between samples).
    uo_last, u2_last, prev_in : float64 [shape=(n_bands,)] state (in/out); uo and u2 are flushed
        every sample.
    started : int64 [shape=(1,)], 0 before the first sample ever (in/out).
    out : float64 [shape=(n_bands, n)], sone/Bark.
    """
    n_bands = core.shape[0]
    n = core.shape[1]
    b0 = coef[0]; b1 = coef[1]; b2 = coef[2]; b3 = coef[3]; b4 = coef[4]; b5 = coef[5]
    inv = 1.0 / n_iter
    for b in range(n_bands):
        uo = uo_last[b]
        u2 = u2_last[b]
        xp = prev_in[b]
        have_prev = started[0] != 0
        for i in range(n):
            xi = core[b, i]
            if have_prev:
                d = (xi - xp) * inv
                for m in range(1, n_iter):
                    uo, u2 = _nl_step(xp + m * d, uo, u2, b0, b1, b2, b3, b4, b5, tol)
            uo, u2 = _nl_step(xi, uo, u2, b0, b1, b2, b3, b4, b5, tol)
            uo = _flush(uo)
            u2 = _flush(u2)
            out[b, i] = uo
            xp = xi
            have_prev = True
        uo_last[b] = uo
        u2_last[b] = u2
        prev_in[b] = xp
    if n > 0:
        started[0] = 1


@numba.njit(**_JIT)
def slopes(core, zup, rns, usl, spec_row, total, spec):
    """Upper slopes: core loudness of 21 critical bands -> N'(z) on 0.1 Bark and total N.

    core : float64 [shape=(21, n)], sone/Bark.
    zup : [shape=(21,)] upper band edges (Bark, already raised by the 1e-4 tolerance);
    rns : [shape=(18,)]; usl : [shape=(18, 8)].
    spec_row : int64 [shape=(n,)]: row of ``spec`` to fill for sample i, or -1 (total only).
    total : float64 [shape=(n,)] out, sone (area under the piecewise-linear pattern).
    spec : float64 [shape=(n_rows, 240)] out, sone/Bark at z = 0.1, 0.2, ... 24.0.
    """
    n = core.shape[1]
    n_bands = core.shape[0]
    n_rns = rns.shape[0]
    n_z = spec.shape[1]
    for t in range(n):
        row = spec_row[t]
        fill = row >= 0
        acc = 0.0
        z1 = 0.0
        n1 = 0.0
        iz = 0
        j = n_rns - 1
        n2 = 0.0
        for i in range(n_bands):
            ig = i - 1
            if ig > 7:
                ig = 7
            nm = core[i, t]
            zu = zup[i]
            while z1 < zu:
                if n1 <= nm:
                    if n1 < nm:  # first j with rns[j] <= nm (rns falls; its last entry is 0)
                        lo = 0
                        hi = n_rns - 1
                        while lo < hi:
                            mid = (lo + hi) // 2
                            if rns[mid] > nm:
                                lo = mid + 1
                            else:
                                hi = mid
                        j = lo
                    z2 = zu
                    n2 = nm
                    acc += n2 * (z2 - z1)
                    if fill:
                        while iz < n_z and (iz + 1) * 0.1 <= z2:
                            spec[row, iz] = n2
                            iz += 1
                else:
                    slope = usl[j, ig]
                    n2 = rns[j]
                    if n2 < nm:
                        n2 = nm
                    dz = (n1 - n2) / slope
                    z2 = z1 + dz
                    if z2 > zu:
                        z2 = zu
                        dz = z2 - z1
                        n2 = n1 - dz * slope
                    acc += dz * (n1 + n2) * 0.5
                    if fill:
                        while iz < n_z and (iz + 1) * 0.1 <= z2:
                            spec[row, iz] = n1 - ((iz + 1) * 0.1 - z1) * slope
                            iz += 1
                if n2 <= rns[j] and j < n_rns - 1:
                    j += 1
                z1 = z2
                n1 = n2
        if acc < 0.0:
            acc = 0.0
        total[t] = acc
        if fill:
            while iz < n_z:
                spec[row, iz] = 0.0
                iz += 1


@numba.njit(**_JIT)
def first_order(x, b_now, b_prev, pole, zi, out):
    """y[i] = b_now x[i] + b_prev x[i-1] + pole y[i-1] (scipy ``lfilter``'s transposed direct form,
    the same arithmetic, the state flushed every sample): x, out float64 [shape=(n,)]; zi float64
    [shape=(1,)], the state (in/out)."""
    z = zi[0]
    for i in range(x.shape[0]):
        v = x[i]
        y = b_now * v + z
        z = _flush(b_prev * v + pole * y)
        out[i] = y
    zi[0] = z


@numba.njit(**_JIT)
def bank_mean_square(x, sos, gain, skip, out):
    """Mean square of each band filter's output over samples skip .. n-1 (stationary levels).

    x : float64 [shape=(n,)], Pa; sos [shape=(n_bands, n_sections, 6)]; gain [shape=(n_bands,)];
    out : float64 [shape=(n_bands,)], Pa^2. Filters start from rest; their states are flushed every
    24 samples (whole signal: any fixed positions do).
    """
    n = x.shape[0]
    n_bands = sos.shape[0]
    n_sec = sos.shape[1]
    zi = np.zeros((n_sec, 2))
    for b in range(n_bands):
        zi[:, :] = 0.0
        acc = 0.0
        for i in range(n):
            v = x[i]
            for s in range(n_sec):
                w = sos[b, s, 0] * v + zi[s, 0]
                zi[s, 0] = sos[b, s, 1] * v - sos[b, s, 4] * w + zi[s, 1]
                zi[s, 1] = sos[b, s, 2] * v - sos[b, s, 5] * w
                v = w
            if i % 24 == 0:
                _flush_sections(zi)
            if i >= skip:
                v = gain[b] * v
                acc += v * v
        out[b] = acc / max(1, n - skip)
