#!/usr/bin/python3
"""Writes src/film/sensor_table.c: pbrt-v4's camera sensors reduced to 3x3 matrices.

Usage: /usr/bin/python3 tools/gen_sensor_table.py PBRT_V4_SOURCE > src/film/sensor_table.c
(needs numpy; reads pbrt-v4's data tables from its source tree, which haze does not ship).

pbrt-v4 renders spectra. A Film "sensor" there is three spectral response
curves; pbrt-v4 fits, by least squares over 24 colour-checker reflectances lit
by the white-balance illuminant, a matrix from the sensor's RGB to XYZ, and
writes output RGB = RGB_from_XYZ * XYZ_from_sensor * sensor RGB. haze renders
linear sRGB, so it needs two 3x3 matrices per sensor:

  sensor_from_render: the sensor's RGB of a haze RGB value. Fitted by least
      squares over a 4x4x4 grid of reflectance colours, each turned into the
      smooth spectrum pbrt-v4 would use for it (a sigmoid of a quadratic,
      solved here by Gauss-Newton) and lit by pbrt-v4's sRGB illuminant (D65);
      white is weighted 100x so greys come out exactly.
  output_from_sensor(T): pbrt-v4's RGB_from_XYZ * XYZ_from_sensor for white
      balance temperature T, computed as pbrt-v4 does (its CIE D illuminant,
      blackbody below 4000 K), tabulated at nodes in mired (1e6/T) over
      1000-50000 K in three pieces split where pbrt-v4's illuminant changes
      formula (7000 K) and jumps (4000 K); haze interpolates with Catmull-Rom
      splines (relative error below 1e-3, mostly 1e-5).

"cie1931" is the XYZ matching functions as a sensor: sensor_from_render is
XYZ_from_RGB and output_from_sensor(T) pbrt-v4's Bradford white balance from
the illuminant's white to D65.

Spectral rendering needs no fit: each camera's three response curves, as
pbrt-v4 gives them (piecewise linear, 380-720 nm every 10 nm, zero outside),
turn a sample's wavelengths into the sensor's RGB directly (curves).
"""
import itertools
import re
import sys

import numpy as np

SEGMENT_NODES = (10, 7, 24)
CURVE_MIN, CURVE_MAX, CURVE_STEP = 380, 720, 10
MIRED_MIN, MIRED_MAX = 20.0, 1000.0


def main(src):
    spec = open(src + '/src/pbrt/util/spectrum.cpp').read()
    film = open(src + '/src/pbrt/film.cpp').read()
    lam = np.arange(360, 831, dtype=float)

    def numbers(text):
        return np.array([float(x) for x in re.findall(r'[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?', text)])

    def table(name):
        m = re.search(r'const Float ' + re.escape(name) + r'\[[^\]]*\]\s*=\s*\{(.*?)\};', spec, re.S)
        return numbers(m.group(1))

    def piecewise(pairs):  # pbrt-v4's piecewise-linear spectra: zero outside their range
        w, v = pairs[0::2], pairs[1::2]
        out = np.interp(lam, w, v)
        out[(lam < w[0]) | (lam > w[-1])] = 0
        return out

    X, Y, Z = table('CIE_X'), table('CIE_Y'), table('CIE_Z')
    s_lam, s0, s1, s2 = table('CIE_S_lambda'), table('CIE_S0'), table('CIE_S1'), table('CIE_S2')
    d65 = piecewise(table('CIE_Illum_D6500'))
    swatch_text = film[film.index('PixelSensor::swatchReflectances'):]
    swatches = [piecewise(numbers(b)) for b in
                re.findall(r'FromInterleaved\(\s*\{(.*?)\}', swatch_text, re.S)[:24]]
    assert len(X) == 471 and len(swatches) == 24

    def illuminant(T):
        cct = T * 1.4388 / 1.4380
        if cct < 4000:
            l, c, h, kb = lam * 1e-9, 299792458.0, 6.62606957e-34, 1.3806488e-23
            return 2 * h * c * c / (l ** 5 * (np.exp(h * c / (l * kb * cct)) - 1))
        if cct <= 7000:
            x = -4.607e9 / cct ** 3 + 2.9678e6 / cct ** 2 + 0.09911e3 / cct + 0.244063
        else:
            x = -2.0064e9 / cct ** 3 + 1.9018e6 / cct ** 2 + 0.24748e3 / cct + 0.23704
        y = -3 * x * x + 2.870 * x - 0.275
        m = 0.0241 + 0.2562 * x - 0.7341 * y
        m1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / m
        m2 = (0.0300 - 31.4424 * x + 30.0717 * y) / m
        return piecewise(np.ravel(np.column_stack([s_lam, (s0 + s1 * m1 + s2 * m2) * 0.01])))

    def xyz_of(s):
        return np.array([X @ s, Y @ s, Z @ s])

    def xyz_from_xy(x, y):
        return np.array([x / y, 1.0, (1 - x - y) / y])

    wxyz = xyz_of(d65)
    white = wxyz[:2] / wxyz.sum()
    prim = np.column_stack([xyz_from_xy(*p) for p in [(.64, .33), (.3, .6), (.15, .06)]])
    xyz_from_rgb = prim * np.linalg.solve(prim, xyz_from_xy(*white))
    rgb_from_xyz = np.linalg.inv(xyz_from_rgb)
    lms_from_xyz = np.array([[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367],
                             [0.0389, -0.0685, 1.0296]])
    xyz_from_lms = np.array([[0.986993, -0.147054, 0.159963], [0.432305, 0.51836, 0.0492912],
                             [-0.00852866, 0.0400428, 0.968487]])

    def white_balance(src_xyz):
        s = lms_from_xyz @ (src_xyz / src_xyz[1])
        d = lms_from_xyz @ xyz_from_xy(*white)
        return xyz_from_lms @ np.diag(d / s) @ lms_from_xyz

    xn = (lam - 360) / 470.0

    def sigmoid_spectrum(c):
        z = c[0] * xn * xn + c[1] * xn + c[2]
        return 0.5 + z / (2 * np.sqrt(1 + z * z))

    def rgb_of_reflectance(s):
        return rgb_from_xyz @ xyz_of(s * d65) / (Y @ d65)

    def upsample(rgb):
        if np.allclose(rgb, rgb[0]):
            return np.full_like(lam, rgb[0])
        c = np.zeros(3)
        for _ in range(200):
            r = rgb_of_reflectance(sigmoid_spectrum(c)) - rgb
            if np.abs(r).max() < 1e-10:
                break
            jac = np.zeros((3, 3))
            for k in range(3):
                d = c.copy()
                d[k] += 1e-6
                jac[:, k] = (rgb_of_reflectance(sigmoid_spectrum(d)) - rgb - r) / 1e-6
            c += np.linalg.lstsq(jac, -r, rcond=None)[0]
        return sigmoid_spectrum(c)

    train = [np.array(g) for g in itertools.product([0.05, 0.3, 0.55, 0.8], repeat=3)]
    train_spectra = [upsample(t) * d65 / (Y @ d65) for t in train] + [d65 / (Y @ d65)]
    train_rgb = np.array(train + [np.ones(3)])
    weight = np.sqrt(np.array([1.0] * len(train) + [100.0]))[:, None]

    def fit_sensor_from_render(curves):
        resp = np.array([[c @ s for c in curves] for s in train_spectra])
        return np.linalg.lstsq(train_rgb * weight, resp * weight, rcond=None)[0].T

    def output_from_sensor(curves, T):
        illum = illuminant(T)
        if curves is None:
            return rgb_from_xyz @ white_balance(xyz_of(illum))
        g = curves[1] @ illum
        a = np.array([[c @ (s * illum) for c in curves] for s in swatches]) / g
        b = np.array([xyz_of(s * d65) for s in swatches]) / (Y @ d65) * ((Y @ illum) / g)
        return rgb_from_xyz @ np.linalg.solve(a.T @ a, a.T @ b).T

    def rows(mat, indent):  # one matrix row a line, to stay within 100 columns
        return (',\n' + ' ' * indent).join(', '.join('%.9g' % v for v in r) for r in mat)

    mired_kink = 1e6 / (7000 * 1.4380 / 1.4388)
    mired_jump = 1e6 / (4000 * 1.4380 / 1.4388)
    segments = [(MIRED_MIN, mired_kink), (mired_kink, mired_jump), (mired_jump, MIRED_MAX)]
    names = ['cie1931'] + re.findall(r'\{"(\w+)_r",', spec)
    out = sys.stdout
    out.write('/* Generated by tools/gen_sensor_table.py from pbrt-v4\'s sensor data; do not edit.\n'
              ' * What the numbers are: see that script and docs/scene-format.md (Film). */\n'
              '#include "film/sensor.h"\n\n')
    out.write('const double sensor_mired_bounds[4] = {%.17g, %.17g, %.17g, %.17g};\n'
              % (MIRED_MIN, mired_kink, mired_jump, MIRED_MAX))
    out.write('const int sensor_segment_nodes[3] = {%d, %d, %d};\n\n' % SEGMENT_NODES)
    nodes = np.arange(CURVE_MIN, CURVE_MAX + 1, CURVE_STEP)
    out.write('const sensor_table_entry sensor_table[SENSOR_TABLE_COUNT] = {\n')
    for name in names:
        curves = None if name == 'cie1931' else [piecewise(table(name + '_' + c)) for c in 'rgb']
        s = xyz_from_rgb if curves is None else fit_sensor_from_render(curves)
        out.write('    {"%s",\n     {%s},\n' % (name, rows(s, 6)))
        if curves is None:
            out.write('     false, {{0}},\n     {\n')
        else:
            native = []
            for c in 'rgb':
                v = table(name + '_' + c)
                assert np.array_equal(v[0::2], nodes), name
                native.append(v[1::2])
            def wrapped(row):  # 6 values a line
                parts = ['%.9g' % x for x in row]
                return ',\n       '.join(', '.join(parts[i:i + 6]) for i in range(0, len(parts), 6))
            out.write('     true,\n     {%s},\n     {\n' % ',\n      '.join(
                '{' + wrapped(row) + '}' for row in native))
        for si, (a, b) in enumerate(segments):
            n = SEGMENT_NODES[si]
            for k in range(n):
                m = a + (b - a) * k / (n - 1)
                # the node at the jump belongs to the segment on its side
                if si == 2 and k == 0:
                    m = np.nextafter(m, np.inf)
                if si == 1 and k == n - 1:
                    m = mired_jump
                mat = output_from_sensor(curves, 1e6 / m)
                out.write('      {%s},\n' % rows(mat, 7))
        out.write('     }},\n')
    out.write('};\n')
    assert len(names) == 18, len(names)


if __name__ == '__main__':
    main(sys.argv[1])
