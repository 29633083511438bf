#include "media/majorant.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* floor(v / c) for a positive c, in 64 bits. */
static int64_t floor_div(int64_t v, int64_t c) { return v >= 0 ? v / c : -((-v + c - 1) / c); }

hz_status majorant_grid_build(const grid *g, vec3 lo, vec3 hi, const int32_t pad[3],
                              majorant_grid *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    out->cell = 8;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z))
        return HZ_OK; /* empty: no cells, every walk misses */
    double l3[3] = {lo.x, lo.y, lo.z}, h3[3] = {hi.x, hi.y, hi.z};
    int64_t first[3], last[3];
    for (int a = 0; a < 3; ++a) { /* index space is int32: so is the support */
        l3[a] = fmin(fmax(l3[a], (double)INT32_MIN), (double)INT32_MAX);
        h3[a] = fmin(fmax(h3[a], (double)INT32_MIN), (double)INT32_MAX);
    }
    for (;;) {
        /* The product in checked arithmetic: voxels 3.3e7 apart once
         * overflowed it. Cells of 2^28 voxels make at most 17 per axis. */
        uint64_t cells = 1;
        for (int a = 0; a < 3; ++a) {
            first[a] = floor_div((int64_t)floor(l3[a]), out->cell);
            last[a] = floor_div((int64_t)floor(h3[a]), out->cell);
            uint64_t res = (uint64_t)(last[a] - first[a] + 1);
            cells = res > (uint64_t)MAJORANT_MAX_CELLS || cells > (uint64_t)MAJORANT_MAX_CELLS
                        ? (uint64_t)MAJORANT_MAX_CELLS + 1
                        : cells * res;
        }
        if (cells <= (uint64_t)MAJORANT_MAX_CELLS || out->cell >= (1 << 28))
            break;
        out->cell *= 2;
    }
    size_t n = 1;
    for (int a = 0; a < 3; ++a) {
        out->res[a] = (int32_t)(last[a] - first[a] + 1);
        out->origin[a] = (int32_t)(first[a] * out->cell);
        n *= (size_t)out->res[a];
    }
    out->max = malloc(n * sizeof *out->max);
    out->min = malloc(n * sizeof *out->min);
    if (!out->max || !out->min) {
        majorant_grid_free(out);
        return hz_fail(err, "out of memory for a majorant grid of %zu cells", n);
    }
    size_t i = 0;
    for (int32_t z = 0; z < out->res[2]; ++z)
        for (int32_t y = 0; y < out->res[1]; ++y)
            for (int32_t x = 0; x < out->res[0]; ++x, ++i) {
                /* Trilinear lookups in [a, a + cell] read voxels a .. a + cell + 1;
                 * one more voxel below absorbs a sample point rounded just out
                 * of its cell. */
                int32_t c3[3] = {x, y, z};
                grid_ibox box;
                for (int a = 0; a < 3; ++a) {
                    int64_t first = (int64_t)out->origin[a] + (int64_t)c3[a] * out->cell;
                    int64_t v0 = first - 1 - pad[a], v1 = first + out->cell + 1 + pad[a];
                    box.min[a] = (int32_t)(v0 < INT32_MIN ? INT32_MIN : v0);
                    box.max[a] = (int32_t)(v1 > INT32_MAX ? INT32_MAX : v1);
                }
                float vmin, vmax;
                grid_region_range(g, box, &vmin, &vmax);
                out->max[i] = fmaxf(vmax, 0.0f);
                out->min[i] = fminf(fmaxf(vmin, 0.0f), out->max[i]);
            }
    return HZ_OK;
}

void majorant_grid_free(majorant_grid *mg)
{
    free(mg->max);
    free(mg->min);
    mg->max = mg->min = NULL;
    mg->res[0] = mg->res[1] = mg->res[2] = 0;
}

size_t majorant_grid_bytes(const majorant_grid *mg)
{
    return (size_t)mg->res[0] * (size_t)mg->res[1] * (size_t)mg->res[2] * 2 * sizeof(float);
}

bool majorant_walk_start(majorant_walk *w, const majorant_grid *mg, vec3 o, vec3 d, double t0,
                         double t1)
{
    w->mg = mg;
    w->done = true;
    if (mg->res[0] <= 0 || !(t0 <= t1))
        return false;
    const double o3[3] = {o.x, o.y, o.z}, d3[3] = {d.x, d.y, d.z};
    /* Clip [t0, t1] to the grid's box (slab test), as cell coordinates
     * u = (p - origin) / cell in [0, res]. */
    double u0[3], du[3];
    for (int a = 0; a < 3; ++a) {
        u0[a] = (o3[a] - mg->origin[a]) / mg->cell;
        du[a] = d3[a] / mg->cell;
        if (du[a] == 0.0) {
            if (!(u0[a] >= 0.0 && u0[a] <= mg->res[a]))
                return false;
            continue;
        }
        double ta = (0.0 - u0[a]) / du[a], tb = (mg->res[a] - u0[a]) / du[a];
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        /* Comparisons, not fmax/fmin (library calls on this hot path); NaN
         * cannot occur: du is finite and non-zero. */
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    if (!(t0 < t1))
        return false;
    /* The cell at the middle of the first step is robust against the entry
     * point rounding onto a face: take the cell of t0, clamped. */
    for (int a = 0; a < 3; ++a) {
        double u = floor(u0[a] + t0 * du[a]);
        int32_t c = u < 0.0 ? 0 : u > mg->res[a] - 1.0 ? mg->res[a] - 1 : (int32_t)u;
        w->ijk[a] = c;
        if (du[a] > 0.0) {
            w->step[a] = 1;
            w->t_next[a] = (c + 1 - u0[a]) / du[a];
            w->t_delta[a] = 1.0 / du[a];
        } else if (du[a] < 0.0) {
            w->step[a] = -1;
            w->t_next[a] = (c - u0[a]) / du[a];
            w->t_delta[a] = -1.0 / du[a];
        } else {
            w->step[a] = 0;
            w->t_next[a] = INFINITY;
            w->t_delta[a] = INFINITY;
        }
    }
    w->t = t0;
    w->t_end = t1;
    w->done = false;
    return true;
}

bool majorant_walk_next(majorant_walk *w, majorant_segment *seg)
{
    if (w->done)
        return false;
    int a = w->t_next[0] < w->t_next[1] ? (w->t_next[0] < w->t_next[2] ? 0 : 2)
                                        : (w->t_next[1] < w->t_next[2] ? 1 : 2);
    double t_exit = w->t_next[a] < w->t_end ? w->t_next[a] : w->t_end;
    const majorant_grid *mg = w->mg;
    size_t i = ((size_t)w->ijk[2] * (size_t)mg->res[1] + (size_t)w->ijk[1]) * (size_t)mg->res[0] +
               (size_t)w->ijk[0];
    seg->t0 = w->t;
    seg->t1 = t_exit > w->t ? t_exit : w->t;
    seg->max = mg->max[i];
    seg->min = mg->min[i];
    w->t = seg->t1;
    if (!(w->t_next[a] < w->t_end)) {
        w->done = true;
        return true;
    }
    w->ijk[a] += w->step[a];
    w->t_next[a] += w->t_delta[a];
    if (w->ijk[a] < 0 || w->ijk[a] >= mg->res[a])
        w->done = true; /* rounding left the box a little early: the rest is outside */
    return true;
}
