#include "media/uniformgrid.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "media/vdb_load.h"

/* nx, ny, nz, p0, p1; returns nx ny nz. */
static size_t read_box(param_list *pl, uniformgrid_params *u)
{
    const char *names[3] = {"nx", "ny", "nz"};
    for (int a = 0; a < 3; ++a) {
        u->n[a] = params_int(pl, names[a], 1);
        if (u->n[a] < 1 || u->n[a] > 1 << 16)
            params_reject(pl, names[a], "\"%s\" must be in [1, 65536], got %d", names[a], u->n[a]);
    }
    u->p0 = params_point3(pl, "p0", v3(0, 0, 0));
    u->p1 = params_point3(pl, "p1", v3(1, 1, 1));
    if (!(u->p0.x < u->p1.x && u->p0.y < u->p1.y && u->p0.z < u->p1.z) ||
        !v3_is_finite(u->p0) || !v3_is_finite(u->p1))
        params_reject(pl, "p1", "the box \"p0\" .. \"p1\" must be finite and non-empty");
    return (size_t)(u->n[0] > 0 ? u->n[0] : 1) * (size_t)(u->n[1] > 0 ? u->n[1] : 1) *
           (size_t)(u->n[2] > 0 ? u->n[2] : 1);
}

void uniformgrid_read(param_list *pl, uniformgrid_params *u)
{
    size_t want = read_box(pl, u);
    const char *arrays[3] = {"density", "temperature", "Lescale"};
    const double **out[3] = {&u->density, &u->temperature, &u->Le_scale};
    for (int k = 0; k < 3; ++k) {
        size_t n = 0;
        *out[k] = params_floats(pl, arrays[k], &n);
        if (*out[k] && n != want) {
            params_reject(pl, arrays[k],
                          "\"%s\" has %zu values; expected nx*ny*nz = %d*%d*%d = %zu", arrays[k],
                          n, u->n[0], u->n[1], u->n[2], want);
            *out[k] = NULL;
        }
    }
    if (!params_has(pl, "density"))
        params_reject(pl, "density", "a \"uniformgrid\" medium needs \"float density\"");
}

hz_status uniformgrid_make(const uniformgrid_params *u, const double *values, size_t count,
                           const char *what, grid **out, hz_error *err)
{
    *out = NULL;
    int n[3] = {u->n[0], u->n[1], u->n[2]};
    if (count == 1)
        n[0] = n[1] = n[2] = 1;
    float *f = malloc(count * sizeof *f);
    if (!f)
        return hz_fail(err, "out of memory for %zu %s values", count, what);
    for (size_t i = 0; i < count; ++i) {
        if (!isfinite(values[i]) || values[i] < 0.0 || values[i] > 3.4e38) {
            free(f);
            return hz_fail(err, "\"%s\" value %zu is %g; values must be finite and >= 0", what, i,
                           values[i]);
        }
        f[i] = (float)values[i];
    }
    /* Sample (i, j, k) at the centre of its cell: p0 + (ijk + 1/2) h. */
    const double p0[3] = {u->p0.x, u->p0.y, u->p0.z}, p1[3] = {u->p1.x, u->p1.y, u->p1.z};
    double scale[3], origin[3];
    for (int a = 0; a < 3; ++a) {
        scale[a] = (p1[a] - p0[a]) / n[a];
        origin[a] = p0[a] + 0.5 * scale[a];
    }
    vdb_buffer buf;
    char msg[512];
    hz_status st = vdb_grid_from_dense(f, n[0], n[1], n[2], scale, origin, what, &buf, msg,
                                       sizeof msg);
    free(f);
    if (st != HZ_OK)
        return hz_fail(err, "%s", msg);
    if (grid_create_from_buffer(&buf, what, out, err) != HZ_OK) {
        vdb_buffer_free(&buf);
        return HZ_ERROR;
    }
    return HZ_OK;
}

void uniformgrid_support(const uniformgrid_params *u, vec3 *lo, vec3 *hi)
{
    *lo = v3(-0.5, -0.5, -0.5);
    *hi = v3(u->n[0] - 0.5, u->n[1] - 0.5, u->n[2] - 0.5);
}

void rgbgrid_read(param_list *pl, rgbgrid_params *r)
{
    *r = (rgbgrid_params){0};
    size_t want = read_box(pl, &r->box);
    const char *arrays[3] = {"sigma_a", "sigma_s", "Le"};
    const double **out[3] = {&r->sigma_a, &r->sigma_s, &r->Le};
    for (int k = 0; k < 3; ++k) {
        size_t n = 0;
        *out[k] = params_rgbs(pl, arrays[k], &n);
        if (*out[k] && n != want) {
            params_reject(pl, arrays[k],
                          "\"%s\" has %zu rgb values; expected nx*ny*nz = %d*%d*%d = %zu",
                          arrays[k], n, r->box.n[0], r->box.n[1], r->box.n[2], want);
            *out[k] = NULL;
        }
    }
    if (!params_has(pl, "sigma_a") && !params_has(pl, "sigma_s"))
        params_reject(pl, "sigma_a", "an \"rgbgrid\" medium needs \"rgb sigma_a\" and/or "
                                     "\"rgb sigma_s\" (as pbrt-v4)");
    if (params_has(pl, "Le") && !params_has(pl, "sigma_a"))
        params_reject(pl, "Le", "\"Le\" needs \"sigma_a\" (as pbrt-v4)");
}

hz_status uniformgrid_make_channel(const uniformgrid_params *u, const double *triples, int c,
                                   const char *what, grid **out, hz_error *err)
{
    size_t count = (size_t)u->n[0] * (size_t)u->n[1] * (size_t)u->n[2];
    double *v = malloc(count * sizeof *v);
    if (!v)
        return hz_fail(err, "out of memory for %zu %s values", count, what);
    for (size_t i = 0; i < count; ++i)
        v[i] = triples[3 * i + (size_t)c];
    hz_status st = uniformgrid_make(u, v, count, what, out, err);
    free(v);
    return st;
}
