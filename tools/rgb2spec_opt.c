/* rgb2spec_opt: writes the RGB -> spectrum coefficient tables of
 * color/rgb2spec_table.h as C source, one table per colour space, by the
 * optimisation of Jakob and Hanika 2019 ("A Low-Dimensional Function Space
 * for Efficient Spectral Upsampling"):
 *
 *   - a reflectance is s(x(u)), x = c0 u^2 + c1 u + c2 with u the wavelength
 *     scaled to [0, 1] over 360..830 nm and s the sigmoid 1/2 + x / (2
 *     sqrt(1 + x^2));
 *   - for each node of the table (largest component, its value z, the other
 *     two as fractions of it) Gauss-Newton finds the c whose colour under
 *     the space's illuminant (CIE 1931 observer, scene/spectrum.h) matches
 *     the node's RGB in CIELAB, starting from the solution of the
 *     neighbouring z, so the coefficients change smoothly along each column;
 *   - the integrals are Simpson's rule on each 5 nm step of the illuminant
 *     table, where the illuminant is linear and the colour matching
 *     functions are cubic.
 *
 * The build runs it (cmake/color.cmake): rgb2spec_opt RES OUT.c OUT.bin
 * [THREADS] writes the floats to OUT.bin and the tables to OUT.c. It
 * prints to stderr, per colour space, the time and the largest CIELAB
 * residual left at a node. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "color/illuminant.h"
#include "core/color_space.h"
#include "scene/spectrum.h"

#define LAMBDA_MIN 360.0
#define LAMBDA_MAX 830.0
enum {
    SEGMENTS = 94,                  /* 5 nm steps over 360..830 nm */
    SUB = 2,                        /* Simpson sub-intervals per step (even) */
    NODES = SEGMENTS * SUB + 1,     /* quadrature nodes */
    MAX_ITERATIONS = 30,
};
#define COEFF_MAX 3000.0  /* |c| bound: keeps unreachable colours finite */
#define CONVERGED 1e-10 /* squared CIELAB residual where Gauss-Newton stops */
#define REPORTED 1e-6    /* squared residual counted as not reached */

typedef struct {
    double u[NODES];    /* (lambda - 360) / 470 */
    double w[NODES][3]; /* XYZ of a reflectance = sum of w * s(u) */
    double white[3];    /* XYZ of the reflectance 1 (Y = 1) */
    double illuminant_scale;
    double xyz_from_rgb[9], rgb_from_xyz[9];
} space_quad;

static void space_quad_init(color_space cs, space_quad *q)
{
    illuminant il = illuminant_of_color_space(cs);
    double h = (LAMBDA_MAX - LAMBDA_MIN) / (NODES - 1), y_bar = 0.0, y_lit = 0.0;
    for (int n = 0; n < NODES; ++n) {
        double lambda = LAMBDA_MIN + n * h;
        int inner = n % SUB; /* Simpson: 1 4 2 4 ... 4 1 within each 5 nm step */
        double qw = (inner == 0 ? (n == 0 || n == NODES - 1 ? 1.0 : 2.0)
                                : (inner % 2 ? 4.0 : 2.0)) * h / 3.0;
        vec3 cmf = spectrum_cie_xyz(lambda);
        double lit = qw * illuminant_raw(il, lambda);
        q->u[n] = (lambda - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN);
        q->w[n][0] = cmf.x * lit;
        q->w[n][1] = cmf.y * lit;
        q->w[n][2] = cmf.z * lit;
        y_bar += qw * cmf.y;
        y_lit += q->w[n][1];
    }
    q->illuminant_scale = y_bar / y_lit;
    memset(q->white, 0, sizeof q->white);
    for (int n = 0; n < NODES; ++n)
        for (int k = 0; k < 3; ++k) {
            q->w[n][k] /= y_lit;
            q->white[k] += q->w[n][k];
        }
    color_space_xyz_from_rgb_white(cs, q->white, q->xyz_from_rgb);
    color_space_rgb_from_xyz_white(cs, q->white, q->rgb_from_xyz);
}

/* The XYZ of the reflectance of coefficients c and its derivatives. */
static void reflectance_xyz(const space_quad *q, const double c[3], double xyz[3],
                            double d[3][3])
{
    memset(xyz, 0, 3 * sizeof *xyz);
    memset(d, 0, 9 * sizeof **d);
    for (int n = 0; n < NODES; ++n) {
        double u = q->u[n], x = (c[0] * u + c[1]) * u + c[2];
        double r = 1.0 / sqrt(1.0 + x * x), s = 0.5 + 0.5 * x * r, ds = 0.5 * r * r * r;
        for (int k = 0; k < 3; ++k) {
            double w = q->w[n][k], t = w * ds;
            xyz[k] += w * s;
            d[k][0] += t * u * u;
            d[k][1] += t * u;
            d[k][2] += t;
        }
    }
}

static double lab_f(double t, double *df)
{
    const double e = 6.0 / 29.0;
    if (t > e * e * e) {
        double c = cbrt(t);
        *df = 1.0 / (3.0 * c * c);
        return c;
    }
    *df = 1.0 / (3.0 * e * e);
    return t / (3.0 * e * e) + 4.0 / 29.0;
}

/* CIELAB of xyz relative to white; d (optional) gets dLab / dXYZ. */
static void lab_from_xyz(const double xyz[3], const double white[3], double lab[3],
                         double d[3][3])
{
    double f[3], df[3];
    for (int k = 0; k < 3; ++k) {
        f[k] = lab_f(xyz[k] / white[k], &df[k]);
        df[k] /= white[k];
    }
    lab[0] = 116.0 * f[1] - 16.0;
    lab[1] = 500.0 * (f[0] - f[1]);
    lab[2] = 200.0 * (f[1] - f[2]);
    if (d) {
        const double m[3][3] = {{0.0, 116.0 * df[1], 0.0},
                                {500.0 * df[0], -500.0 * df[1], 0.0},
                                {0.0, 200.0 * df[1], -200.0 * df[2]}};
        memcpy(d, m, sizeof m);
    }
}

/* target - Lab(c) in r and dLab(c)/dc in jac; returns |r|^2. */
static double residual(const space_quad *q, const double target[3], const double c[3],
                       double r[3], double jac[3][3])
{
    double xyz[3], dxyz[3][3], lab[3], dlab[3][3];
    reflectance_xyz(q, c, xyz, dxyz);
    lab_from_xyz(xyz, q->white, lab, dlab);
    double r2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        r[i] = target[i] - lab[i];
        r2 += r[i] * r[i];
        for (int j = 0; j < 3; ++j)
            jac[i][j] = dlab[i][0] * dxyz[0][j] + dlab[i][1] * dxyz[1][j] + dlab[i][2] * dxyz[2][j];
    }
    return r2;
}

/* a x = b by elimination with partial pivoting; false when singular. */
static int solve3(double a[3][3], double b[3], double x[3])
{
    for (int col = 0; col < 3; ++col) {
        int p = col;
        for (int r = col + 1; r < 3; ++r)
            if (fabs(a[r][col]) > fabs(a[p][col]))
                p = r;
        if (!(fabs(a[p][col]) > 1e-300))
            return 0;
        for (int j = 0; j < 3; ++j) {
            double t = a[col][j];
            a[col][j] = a[p][j];
            a[p][j] = t;
        }
        double t = b[col];
        b[col] = b[p];
        b[p] = t;
        for (int r = col + 1; r < 3; ++r) {
            double f = a[r][col] / a[col][col];
            for (int j = col; j < 3; ++j)
                a[r][j] -= f * a[col][j];
            b[r] -= f * b[col];
        }
    }
    for (int i = 2; i >= 0; --i) {
        double s = b[i];
        for (int j = i + 1; j < 3; ++j)
            s -= a[i][j] * x[j];
        x[i] = s / a[i][i];
    }
    return 1;
}

static void clamp_coeffs(double c[3])
{
    double m = fmax(fabs(c[0]), fmax(fabs(c[1]), fabs(c[2])));
    if (m > COEFF_MAX)
        for (int i = 0; i < 3; ++i)
            c[i] *= COEFF_MAX / m;
}

/* Gauss-Newton from c towards the CIELAB target, each step halved until the
 * residual falls (at most 5 times); returns the final squared residual. */
static double gauss_newton(const space_quad *q, const double target[3], double c[3])
{
    double r[3], jac[3][3];
    double r2 = residual(q, target, c, r, jac);
    for (int it = 0; it < MAX_ITERATIONS && r2 > CONVERGED; ++it) {
        double step[3], tried[3], rn[3], jn[3][3], r2n = r2;
        if (!solve3(jac, r, step))
            break;
        double t = 1.0;
        for (int halvings = 0; halvings <= 5; ++halvings, t *= 0.5) {
            for (int i = 0; i < 3; ++i)
                tried[i] = c[i] + t * step[i];
            clamp_coeffs(tried);
            r2n = residual(q, target, tried, rn, jn);
            if (r2n < r2)
                break;
        }
        if (!(r2n < r2))
            break; /* no descent: the colour is out of the family's reach */
        memcpy(c, tried, sizeof tried);
        memcpy(r, rn, sizeof rn);
        memcpy(jac, jn, sizeof jn);
        r2 = r2n;
    }
    return r2;
}

typedef struct {
    const space_quad *q;
    int res;
    const double *z_nodes, *xy_nodes;
    float *out;             /* [3][res][res][res][3] */
    atomic_int next;        /* next (component, j) row to solve */
    pthread_mutex_t lock;   /* guards the statistics below */
    double worst;
    long missed;
} job;

/* Coefficients over u in [0, 1] as coefficients over lambda in nm. */
static void store(float *dst, const double c[3])
{
    const double a = 1.0 / (LAMBDA_MAX - LAMBDA_MIN), b = LAMBDA_MIN * a;
    dst[0] = (float)(c[0] * a * a);
    dst[1] = (float)(c[1] * a - 2.0 * c[0] * a * b);
    dst[2] = (float)(c[2] - c[1] * b + c[0] * b * b);
}

/* Solves the node (m, k, j, i) from c (updated); returns its residual. */
static double solve_node(job *jb, int m, int k, int j, int i, double c[3])
{
    double z = jb->z_nodes[k], rgb[3], xyz[3], lab[3];
    rgb[m] = z;
    rgb[(m + 1) % 3] = z * jb->xy_nodes[i];
    rgb[(m + 2) % 3] = z * jb->xy_nodes[j];
    const double *a = jb->q->xyz_from_rgb;
    for (int r = 0; r < 3; ++r)
        xyz[r] = a[3 * r] * rgb[0] + a[3 * r + 1] * rgb[1] + a[3 * r + 2] * rgb[2];
    lab_from_xyz(xyz, jb->q->white, lab, NULL);
    double r2 = gauss_newton(jb->q, lab, c);
    int res = jb->res;
    store(jb->out + 3 * (((size_t)(m * res + k) * res + j) * res + i), c);
    return r2;
}

/* One column of z for (m, j, i): up from a fifth of the way, where the
 * grey start is near, then down from there. */
static void solve_column(job *jb, int m, int j, int i, double *worst, long *missed)
{
    int res = jb->res, start = res / 5;
    double c[3] = {0.0, 0.0, 0.0}, at_start[3];
    for (int k = start; k < res; ++k) {
        double r2 = solve_node(jb, m, k, j, i, c);
        if (k == start)
            memcpy(at_start, c, sizeof c);
        *worst = fmax(*worst, r2);
        *missed += r2 > REPORTED;
    }
    memcpy(c, at_start, sizeof c);
    for (int k = start - 1; k >= 1; --k) {
        double r2 = solve_node(jb, m, k, j, i, c);
        *worst = fmax(*worst, r2);
        *missed += r2 > REPORTED;
    }
    /* z = 0 is black, which no sigmoid reaches: the row takes the darkest
     * solved spectra, whose colours are within z_nodes[1] (~1e-6) of it. */
    store(jb->out + 3 * (((size_t)m * res * res + j) * res + i), c);
}

static void *worker(void *arg)
{
    job *jb = arg;
    double worst = 0.0;
    long missed = 0;
    for (;;) {
        int row = atomic_fetch_add(&jb->next, 1);
        if (row >= 3 * jb->res)
            break;
        for (int i = 0; i < jb->res; ++i)
            solve_column(jb, row / jb->res, row % jb->res, i, &worst, &missed);
    }
    pthread_mutex_lock(&jb->lock);
    jb->worst = fmax(jb->worst, worst);
    jb->missed += missed;
    pthread_mutex_unlock(&jb->lock);
    return NULL;
}

static double smoothstep(double x) { return x * x * (3.0 - 2.0 * x); }

/* The node positions, rounded to float as the table holds them: pbrt-v4's
 * smoothstep(smoothstep(t)) for the largest component, dense where the
 * spectra approach 0 and 1; the same for the other two as fractions of it
 * (pbrt-v4 spaces those evenly), dense towards a zero component and towards
 * the largest, where the coefficients change fastest: at 64 nodes it halves
 * the largest round-trip error of even spacing (docs/spectral.md). */
static void nodes_of(int res, double *z, double *xy)
{
    for (int k = 0; k < res; ++k) {
        z[k] = (float)smoothstep(smoothstep(k / (double)(res - 1)));
        xy[k] = z[k];
    }
}

/* Fills out ([3][res]^3[3]) for one colour space with `threads` threads;
 * false when a thread cannot start. */
static int optimise(const space_quad *q, int res, int threads, float *out, double *worst,
                    long *missed)
{
    double *z = malloc(sizeof *z * 2 * (size_t)res);
    if (!z)
        return 0;
    nodes_of(res, z, z + res);
    job jb = {.q = q, .res = res, .z_nodes = z, .xy_nodes = z + res, .out = out, .worst = 0.0, .missed = 0};
    atomic_init(&jb.next, 0);
    pthread_mutex_init(&jb.lock, NULL);
    pthread_t tid[64];
    int started = 0, ok = 1;
    for (; started < threads - 1; ++started)
        if (pthread_create(&tid[started], NULL, worker, &jb) != 0) {
            ok = 0;
            break;
        }
    worker(&jb);
    for (int t = 0; t < started; ++t)
        pthread_join(tid[t], NULL);
    pthread_mutex_destroy(&jb.lock);
    free(z);
    *worst = jb.worst;
    *missed = jb.missed;
    return ok;
}

static void write_doubles(FILE *f, const double *v, int n)
{
    fputc('{', f);
    for (int i = 0; i < n; ++i)
        fprintf(f, "%s%.17g", i ? ", " : "", v[i]);
    fputc('}', f);
}

/* Appends the nodes and coefficients of one table to the blob; false when
 * the write fails. */
static int write_blob(FILE *blob, int res, const float *out)
{
    double *nodes = malloc(sizeof *nodes * 2 * (size_t)res);
    float *z = malloc(sizeof *z * 2 * (size_t)res);
    int ok = nodes && z;
    if (ok) {
        nodes_of(res, nodes, nodes + res);
        for (int k = 0; k < 2 * res; ++k)
            z[k] = (float)nodes[k];
        size_t n = (size_t)9 * res * res * res;
        ok = fwrite(z, sizeof *z, 2 * (size_t)res, blob) == 2 * (size_t)res &&
             fwrite(out, sizeof *out, n, blob) == n;
    }
    free(z);
    free(nodes);
    return ok;
}

/* The table of colour space cs, whose floats start at `at` in the blob. */
static void write_entry(FILE *f, int cs, int res, size_t at, const space_quad *q)
{
    fprintf(f, "    [%d] = {%d, rgb2spec_blob + %zu, rgb2spec_blob + %zu, rgb2spec_blob + %zu,\n"
               "        %.17g,\n        ",
            cs, res, at, at + (size_t)res, at + 2 * (size_t)res, q->illuminant_scale);
    write_doubles(f, q->white, 3);
    fprintf(f, ",\n        ");
    write_doubles(f, q->xyz_from_rgb, 9);
    fprintf(f, ",\n        ");
    write_doubles(f, q->rgb_from_xyz, 9);
    fprintf(f, "},\n");
}

/* The C source: the blob assembled in with .incbin (an initialiser of the
 * same 9.4 million floats costs gcc 30 s and 2 GB at RES 64) and the tables
 * pointing into it. */
static void write_source(FILE *f, int res, const char *blob_path, const space_quad *quads)
{
    fprintf(f, "/* Generated by `rgb2spec_opt %d` (tools/rgb2spec_opt.c); do not edit. */\n"
               "#include \"color/rgb2spec_table.h\"\n\n"
               "/* The floats of every table, in this machine's byte order. */\n"
               "__asm__(\".section .rodata\\n\"\n"
               "        \".balign 64\\n\"\n"
               "        \".globl haze_rgb2spec_blob\\n\"\n"
               "        \"haze_rgb2spec_blob:\\n\"\n"
               "        \".incbin \\\"",
            res);
    for (const char *c = blob_path; *c; ++c) /* escaped for C, then for the assembler */
        fprintf(f, "%s", *c == '"' ? "\\\\\\\"" : *c == '\\' ? "\\\\\\\\" : (char[2]){*c, 0});
    fprintf(f, "\\\"\\n\"\n        \".previous\\n\");\n"
               "extern const float haze_rgb2spec_blob[];\n"
               "#define rgb2spec_blob haze_rgb2spec_blob\n\n"
               "const rgb2spec_table rgb2spec_tables[COLOR_SPACE_COUNT] = {\n");
    size_t per_space = 2 * (size_t)res + (size_t)9 * res * res * res;
    for (int cs = 0; cs < COLOR_SPACE_COUNT; ++cs)
        write_entry(f, cs, res, cs * per_space, &quads[cs]);
    fprintf(f, "};\n");
}

static double seconds_since(const struct timespec *t0)
{
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
}

static int parse_int(const char *s, int lo, int hi, int *out)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < lo || v > hi)
        return 0;
    *out = (int)v;
    return 1;
}

/* Solves every colour space's table into `out` and appends it to the blob. */
static int solve_all(FILE *blob, int res, int threads, float *out, space_quad *quads)
{
    for (int cs = 0; cs < COLOR_SPACE_COUNT; ++cs) {
        struct timespec t0;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        double worst;
        long missed;
        space_quad_init((color_space)cs, &quads[cs]);
        if (!optimise(&quads[cs], res, threads, out, &worst, &missed)) {
            fprintf(stderr, "rgb2spec_opt: cannot start a thread\n");
            return 0;
        }
        fprintf(stderr, "rgb2spec_opt: %s: %d^3 x 3 nodes in %.1f s (%d threads), "
                "largest CIELAB residual %.3g, %ld nodes above %.0e\n",
                color_space_name((color_space)cs), res, seconds_since(&t0), threads,
                sqrt(worst), missed, sqrt(REPORTED));
        if (!write_blob(blob, res, out)) {
            fprintf(stderr, "rgb2spec_opt: cannot write the table\n");
            return 0;
        }
    }
    return 1;
}

int main(int argc, char **argv)
{
    int res = 0, threads = (int)sysconf(_SC_NPROCESSORS_ONLN);
    threads = threads < 1 ? 1 : threads > 64 ? 64 : threads;
    if (argc < 4 || argc > 5 || !parse_int(argv[1], 4, 256, &res) ||
        (argc == 5 && !parse_int(argv[4], 1, 64, &threads))) {
        fprintf(stderr, "usage: rgb2spec_opt RES (4..256) OUT.c OUT.bin [THREADS (1..64)]\n");
        return 2;
    }
    char tmp_c[4096], tmp_bin[4096];
    snprintf(tmp_c, sizeof tmp_c, "%s.tmp", argv[2]);
    snprintf(tmp_bin, sizeof tmp_bin, "%s.tmp", argv[3]);
    FILE *f = fopen(tmp_c, "w"), *blob = fopen(tmp_bin, "wb");
    float *out = malloc(sizeof *out * (size_t)9 * res * res * res);
    static space_quad quads[COLOR_SPACE_COUNT];
    if (!f || !blob || !out) {
        fprintf(stderr, "rgb2spec_opt: cannot write %s and %s\n", argv[2], argv[3]);
        return 1;
    }
    int ok = solve_all(blob, res, threads, out, quads);
    free(out);
    if (ok)
        write_source(f, res, argv[3], quads);
    if (fclose(blob) != 0 || fclose(f) != 0 || !ok || rename(tmp_bin, argv[3]) != 0 ||
        rename(tmp_c, argv[2]) != 0) {
        fprintf(stderr, "rgb2spec_opt: cannot write %s and %s\n", argv[2], argv[3]);
        return 1;
    }
    return 0;
}
