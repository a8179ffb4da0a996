"""Numerical tables of ISO 532-1:2017 (Zwicker loudness) and DIN 45692:2009 (sharpness).

These numbers are facts of the standards (ISO 532-1 Annex A, tables A.1-A.9, and clause 6 time
constants; DIN 45692 clause 5), transcribed here once. Nothing in this module computes anything.
Index conventions: third-octave bands 0..27 are 25 Hz .. 12.5 kHz; critical bands 0..20 follow
ISO's approximated critical bands whose upper edges are ``ZUP``.
"""

from __future__ import annotations

import numpy as np

# ---------------------------------------------------------------- third-octave filter bank
SAMPLE_RATE_HZ = 48_000  # ISO 532-1 filters are specified at 48 kHz only
N_THIRD_OCTAVE_BANDS = 28

# Exact centre frequencies: 1 kHz * 10**((i - 16) / 10), i = 0..27 (25 Hz .. 12.5 kHz nominal).
CENTRE_FREQUENCIES_HZ = 1000.0 * 10.0 ** ((np.arange(N_THIRD_OCTAVE_BANDS) - 16) / 10.0)

# Table A.1: reference second-order sections (b0 b1 b2 a0 a1 a2), three per band filter.
FILTER_REFERENCE_SOS = np.array([
    [1.0, 2.0, 1.0, 1.0, -2.0, 1.0],
    [1.0, 0.0, -1.0, 1.0, -2.0, 1.0],
    [1.0, -2.0, 1.0, 1.0, -2.0, 1.0],
])

# Table A.2: per band and section, the (a1, a2) differences to subtract from the reference
# sections: a1 = -2 - d1, a2 = 1 - d2.
FILTER_A_DIFFERENCES = np.array([
    [[-6.70260e-04, 6.59453e-04], [-3.75071e-04, 3.61926e-04], [-3.06523e-04, 2.97634e-04]],
    [[-8.47258e-04, 8.30131e-04], [-4.76448e-04, 4.55616e-04], [-3.88773e-04, 3.74685e-04]],
    [[-1.07210e-03, 1.04496e-03], [-6.06567e-04, 5.73553e-04], [-4.94004e-04, 4.71677e-04]],
    [[-1.35836e-03, 1.31535e-03], [-7.74327e-04, 7.22007e-04], [-6.29154e-04, 5.93771e-04]],
    [[-1.72380e-03, 1.65564e-03], [-9.91780e-04, 9.08866e-04], [-8.03529e-04, 7.47455e-04]],
    [[-2.19188e-03, 2.08388e-03], [-1.27545e-03, 1.14406e-03], [-1.02976e-03, 9.40900e-04]],
    [[-2.79386e-03, 2.62274e-03], [-1.64828e-03, 1.44006e-03], [-1.32520e-03, 1.18438e-03]],
    [[-3.57182e-03, 3.30071e-03], [-2.14252e-03, 1.81258e-03], [-1.71397e-03, 1.49082e-03]],
    [[-4.58305e-03, 4.15355e-03], [-2.80413e-03, 2.28135e-03], [-2.23006e-03, 1.87646e-03]],
    [[-5.90655e-03, 5.22622e-03], [-3.69947e-03, 2.87118e-03], [-2.92205e-03, 2.36178e-03]],
    [[-7.65243e-03, 6.57493e-03], [-4.92540e-03, 3.61318e-03], [-3.86007e-03, 2.97240e-03]],
    [[-1.00023e-02, 8.29610e-03], [-6.63788e-03, 4.55999e-03], [-5.15982e-03, 3.75306e-03]],
    [[-1.31230e-02, 1.04220e-02], [-9.02274e-03, 5.73132e-03], [-6.94543e-03, 4.71734e-03]],
    [[-1.73693e-02, 1.30947e-02], [-1.24176e-02, 7.20526e-03], [-9.46002e-03, 5.93145e-03]],
    [[-2.31934e-02, 1.64308e-02], [-1.73009e-02, 9.04761e-03], [-1.30358e-02, 7.44926e-03]],
    [[-3.13292e-02, 2.06370e-02], [-2.44342e-02, 1.13731e-02], [-1.82108e-02, 9.36778e-03]],
    [[-4.28261e-02, 2.59325e-02], [-3.49619e-02, 1.43046e-02], [-2.57855e-02, 1.17912e-02]],
    [[-5.91733e-02, 3.25054e-02], [-5.06072e-02, 1.79513e-02], [-3.69401e-02, 1.48094e-02]],
    [[-8.26348e-02, 4.05894e-02], [-7.40348e-02, 2.24476e-02], [-5.34977e-02, 1.85371e-02]],
    [[-1.17018e-01, 5.08116e-02], [-1.09516e-01, 2.81387e-02], [-7.85097e-02, 2.32872e-02]],
    [[-1.67714e-01, 6.37872e-02], [-1.63378e-01, 3.53729e-02], [-1.16419e-01, 2.93723e-02]],
    [[-2.42528e-01, 7.98576e-02], [-2.45161e-01, 4.43370e-02], [-1.73972e-01, 3.70015e-02]],
    [[-3.53142e-01, 9.96330e-02], [-3.69163e-01, 5.53535e-02], [-2.61399e-01, 4.65428e-02]],
    [[-5.16316e-01, 1.24177e-01], [-5.55473e-01, 6.89403e-02], [-3.93998e-01, 5.86715e-02]],
    [[-7.56635e-01, 1.55023e-01], [-8.34281e-01, 8.58123e-02], [-5.94547e-01, 7.43960e-02]],
    [[-1.10165e+00, 1.91713e-01], [-1.23939e+00, 1.05243e-01], [-8.91666e-01, 9.40354e-02]],
    [[-1.58477e+00, 2.39049e-01], [-1.80505e+00, 1.28794e-01], [-1.32500e+00, 1.21333e-01]],
    [[-2.50630e+00, 1.42308e-01], [-2.19464e+00, 2.76470e-01], [-1.90231e+00, 1.47304e-01]],
])

# Table A.2: overall gain of each band filter.
FILTER_GAINS = np.array([
    4.30764e-11, 8.59340e-11, 1.71424e-10, 3.41944e-10, 6.82035e-10, 1.36026e-09, 2.71261e-09,
    5.40870e-09, 1.07826e-08, 2.14910e-08, 4.28228e-08, 8.54316e-08, 1.70009e-07, 3.38215e-07,
    6.71990e-07, 1.33531e-06, 2.65172e-06, 5.25477e-06, 1.03780e-05, 2.04870e-05, 4.05198e-05,
    7.97914e-05, 1.56511e-04, 3.04954e-04, 5.99157e-04, 1.16544e-03, 2.27488e-03, 3.91006e-03,
])

# Clause 6.3: three cascaded first-order low-pass filters smooth the squared band signal with
# tau = 2 / (3 fc) for fc <= 1 kHz and tau = 2 / (3 * 1 kHz) above.
SMOOTHING_CORNER_HZ = 1000.0
N_SMOOTHING_POLES = 3

LEVEL_RATE_HZ = 2000  # internal rate of levels, core loudness and decay (0.5 ms)
LOUDNESS_RATE_HZ = 500  # output rate of N(t) and N'(z, t) (2 ms)
INTENSITY_REF = 4e-10  # (20 uPa)^2, Pa^2
TINY_INTENSITY = 1e-12  # Pa^2 added before the logarithm

# ---------------------------------------------------------------- core loudness (A.3-A.7)
MAX_LOW_FREQUENCY_LEVEL_DB = 120.0  # Table A.3 is specified for levels up to 120 dB (bands <= 250 Hz)
N_LOW_BANDS = 11  # third-octave bands 25 Hz .. 250 Hz are corrected and merged into 3 critical bands

# Table A.3: level ranges (dB) and reductions (dB) of the 11 lowest third-octave bands
# according to the equal-loudness contours.
RAP = np.array([45.0, 55.0, 65.0, 71.0, 80.0, 90.0, 100.0, 120.0])
DLL = np.array([
    [-32, -24, -16, -10, -5, 0, -7, -3, 0, -2, 0],
    [-29, -22, -15, -10, -4, 0, -7, -2, 0, -2, 0],
    [-27, -19, -14, -9, -4, 0, -6, -2, 0, -2, 0],
    [-25, -17, -12, -9, -3, 0, -5, -2, 0, -2, 0],
    [-23, -16, -11, -7, -3, 0, -4, -1, 0, -1, 0],
    [-20, -14, -10, -6, -3, 0, -4, -1, 0, -1, 0],
    [-18, -12, -9, -6, -2, 0, -3, -1, 0, -1, 0],
    [-15, -10, -8, -4, -2, 0, -3, -1, 0, -1, 0],
], dtype=np.float64)
# Third-octave bands summed into the first three critical bands: [0, 6), [6, 9), [9, 11).
LOW_CRITICAL_BAND_EDGES = (0, 6, 9, 11)
FIRST_HIGH_BAND = 8  # critical band i >= 3 takes third-octave band i + 8 (315 Hz ...)

N_CORE_BANDS = 20  # critical bands with a level; a 21st band (24 Bark) is always 0
# Table A.4: attenuation of the transmission through the outer and middle ear (dB).
A0 = np.array([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, -0.5, -1.6, -3.2, -5.4, -5.6, -4, -1.5, 2, 5, 12],
              dtype=np.float64)
# Table A.5: level difference diffuse minus free field (dB).
DDF = np.array([0, 0, 0.5, 0.9, 1.2, 1.6, 2.3, 2.8, 3, 2, 0, -1.4, -2, -1.9, -1, 0.5, 3, 4, 4.3, 4],
               dtype=np.float64)
# Table A.6: critical band level at the threshold in quiet (dB).
LTQ = np.array([30, 18, 12, 8, 7, 6, 5, 4, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3], dtype=np.float64)
# Table A.7: adaptation of third-octave levels to critical band levels (dB).
DCB = np.array([-0.25, -0.6, -0.8, -0.8, -0.5, 0, 0.5, 1.1, 1.5, 1.7, 1.8, 1.8, 1.7, 1.6, 1.4, 1.2,
                0.8, 0.5, 0, -0.5])
CORE_EXPONENT_S = 0.25  # the constant s of the core loudness formula
CORE_FACTOR = 0.0635  # sone/Bark

# ---------------------------------------------------------------- nonlinear decay (clause 6.5)
NL_T_SHORT_S = 0.005
NL_T_LONG_S = 0.015
NL_T_VAR_S = 0.075
NL_ITERATIONS = 24  # linear interpolation steps per 2 kHz sample (48 kHz virtual rate)
NL_EQUAL_TOLERANCE = 1e-5  # sone/Bark; "input equals previous output" test of the decay network

# ---------------------------------------------------------------- slopes (A.8, A.9)
N_BARK = 240
BARK_STEP = 0.1
BARK_AXIS = np.round(np.arange(1, N_BARK + 1) * BARK_STEP, 10)  # 0.1 .. 24.0 Bark
ZUP = np.array([0.9, 1.8, 2.8, 3.5, 4.4, 5.4, 6.6, 7.9, 9.2, 10.6, 12.3, 13.8, 15.2, 16.7, 18.1, 19.3,
                20.6, 21.8, 22.7, 23.6, 24.0])
ZUP_EPS = 1e-4  # added to ZUP so that the grid point z = ZUP is filled by the band below it
RNS = np.array([21.5, 18, 15.1, 11.5, 9, 6.1, 4.4, 3.1, 2.13, 1.36, 0.82, 0.42, 0.30, 0.22, 0.15,
                0.10, 0.035, 0])
USL = np.array([
    [13, 8.2, 6.3, 5.5, 5.5, 5.5, 5.5, 5.5],
    [9, 7.5, 6, 5.1, 4.5, 4.5, 4.5, 4.5],
    [7.8, 6.7, 5.6, 4.9, 4.4, 3.9, 3.9, 3.9],
    [6.2, 5.4, 4.6, 4.0, 3.5, 3.2, 3.2, 3.2],
    [4.5, 3.8, 3.6, 3.2, 2.9, 2.7, 2.7, 2.7],
    [3.7, 3.0, 2.8, 2.35, 2.2, 2.2, 2.2, 2.2],
    [2.9, 2.3, 2.1, 1.9, 1.8, 1.7, 1.7, 1.7],
    [2.4, 1.7, 1.5, 1.35, 1.3, 1.3, 1.3, 1.3],
    [1.95, 1.45, 1.3, 1.15, 1.1, 1.1, 1.1, 1.1],
    [1.5, 1.2, 0.94, 0.86, 0.82, 0.82, 0.82, 0.82],
    [0.72, 0.67, 0.64, 0.63, 0.62, 0.62, 0.62, 0.62],
    [0.59, 0.53, 0.51, 0.50, 0.42, 0.42, 0.42, 0.42],
    [0.40, 0.33, 0.26, 0.24, 0.24, 0.22, 0.22, 0.22],
    [0.27, 0.21, 0.20, 0.18, 0.17, 0.17, 0.17, 0.17],
    [0.16, 0.15, 0.14, 0.12, 0.11, 0.11, 0.11, 0.11],
    [0.12, 0.11, 0.10, 0.08, 0.08, 0.08, 0.08, 0.08],
    [0.09, 0.08, 0.07, 0.06, 0.06, 0.06, 0.06, 0.05],
    [0.06, 0.05, 0.03, 0.02, 0.02, 0.02, 0.02, 0.02],
])  # sone/Bark per Bark; rows follow RNS, columns the critical band below the slope (capped at 7)

# ---------------------------------------------------------------- temporal weighting (6.7)
TW_TAU_SHORT_S = 3.5e-3
TW_TAU_LONG_S = 70e-3
TW_WEIGHT_SHORT = 0.47
TW_WEIGHT_LONG = 0.53
TW_ITERATIONS = 24  # linear interpolation steps per 2 kHz sample

# ---------------------------------------------------------------- DIN 45692 sharpness
DIN_SHARPNESS_K = 0.11  # acum per Bark: the k of S = k * int N'(z) g(z) z dz / N
DIN_G_KNEE_BARK = 15.8  # g(z) = 1 below, 0.15 exp(0.42 (z - 15.8)) + 0.85 above
DIN_G_A = 0.15
DIN_G_B = 0.42
DIN_G_C = 0.85
