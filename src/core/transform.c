#include "core/transform.h"

#include <math.h>
#include <string.h>

mat4 mat4_identity(void)
{
    mat4 r;
    memset(&r, 0, sizeof r);
    for (int i = 0; i < 4; ++i)
        r.m[i][i] = 1.0;
    return r;
}

mat4 mat4_mul(mat4 a, mat4 b)
{
    mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j] +
                        a.m[i][3] * b.m[3][j];
    return r;
}

mat4 mat4_transpose(mat4 a)
{
    mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            r.m[i][j] = a.m[j][i];
    return r;
}

/* Gauss-Jordan elimination with partial pivoting. */
bool mat4_inverse(mat4 a, mat4 *out)
{
    mat4 inv = mat4_identity();
    for (int col = 0; col < 4; ++col) {
        int pivot = col;
        for (int r = col + 1; r < 4; ++r)
            if (fabs(a.m[r][col]) > fabs(a.m[pivot][col]))
                pivot = r;
        if (a.m[pivot][col] == 0.0 || !isfinite(a.m[pivot][col]))
            return false;
        if (pivot != col) {
            for (int j = 0; j < 4; ++j) {
                double t = a.m[col][j];
                a.m[col][j] = a.m[pivot][j];
                a.m[pivot][j] = t;
                t = inv.m[col][j];
                inv.m[col][j] = inv.m[pivot][j];
                inv.m[pivot][j] = t;
            }
        }
        double s = 1.0 / a.m[col][col];
        for (int j = 0; j < 4; ++j) {
            a.m[col][j] *= s;
            inv.m[col][j] *= s;
        }
        for (int r = 0; r < 4; ++r) {
            if (r == col)
                continue;
            double f = a.m[r][col];
            if (f == 0.0)
                continue;
            for (int j = 0; j < 4; ++j) {
                a.m[r][j] -= f * a.m[col][j];
                inv.m[r][j] -= f * inv.m[col][j];
            }
        }
    }
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (!isfinite(inv.m[i][j]))
                return false;
    *out = inv;
    return true;
}

transform transform_identity(void)
{
    return (transform){mat4_identity(), mat4_identity()};
}

bool transform_from_matrix(mat4 m, transform *out)
{
    mat4 inv;
    if (!mat4_inverse(m, &inv))
        return false;
    out->m = m;
    out->m_inv = inv;
    return true;
}

transform transform_inverse(transform t)
{
    return (transform){t.m_inv, t.m};
}

transform transform_compose(transform a_from_b, transform b_from_c)
{
    return (transform){mat4_mul(a_from_b.m, b_from_c.m), mat4_mul(b_from_c.m_inv, a_from_b.m_inv)};
}

bool transform_is_identity(transform t)
{
    /* Compare values, not bytes: products of exact transforms leave -0.0 entries
     * (e.g. Scale(-1,1,1) twice), which are still the identity. */
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (t.m.m[i][j] != (i == j ? 1.0 : 0.0))
                return false;
    return true;
}

transform transform_translate(vec3 d)
{
    transform t = transform_identity();
    t.m.m[0][3] = d.x;
    t.m.m[1][3] = d.y;
    t.m.m[2][3] = d.z;
    t.m_inv.m[0][3] = -d.x;
    t.m_inv.m[1][3] = -d.y;
    t.m_inv.m[2][3] = -d.z;
    return t;
}

transform transform_scale(vec3 s)
{
    transform t = transform_identity();
    t.m.m[0][0] = s.x;
    t.m.m[1][1] = s.y;
    t.m.m[2][2] = s.z;
    t.m_inv.m[0][0] = 1.0 / s.x;
    t.m_inv.m[1][1] = 1.0 / s.y;
    t.m_inv.m[2][2] = 1.0 / s.z;
    return t;
}

transform transform_rotate(double degrees, vec3 axis)
{
    vec3 a = v3_normalize(axis);
    double theta = hz_radians(degrees);
    double s = sin(theta), c = cos(theta);
    mat4 m = mat4_identity();
    m.m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
    m.m[0][1] = a.x * a.y * (1 - c) - a.z * s;
    m.m[0][2] = a.x * a.z * (1 - c) + a.y * s;
    m.m[1][0] = a.x * a.y * (1 - c) + a.z * s;
    m.m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
    m.m[1][2] = a.y * a.z * (1 - c) - a.x * s;
    m.m[2][0] = a.x * a.z * (1 - c) - a.y * s;
    m.m[2][1] = a.y * a.z * (1 - c) + a.x * s;
    m.m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
    return (transform){m, mat4_transpose(m)};
}

bool transform_look_at(vec3 eye, vec3 look, vec3 up, transform *camera_from_world)
{
    vec3 d = v3_sub(look, eye);
    double up_len = v3_length(up);
    if (v3_length(d) == 0.0 || up_len == 0.0 || !v3_is_finite(d) || !v3_is_finite(up))
        return false;
    vec3 dir = v3_normalize(d);
    vec3 right = v3_cross(v3_scale(up, 1.0 / up_len), dir);
    if (v3_length(right) == 0.0)
        return false;
    right = v3_normalize(right);
    vec3 new_up = v3_cross(dir, right);
    mat4 world_from_camera = mat4_identity();
    world_from_camera.m[0][0] = right.x;
    world_from_camera.m[1][0] = right.y;
    world_from_camera.m[2][0] = right.z;
    world_from_camera.m[0][1] = new_up.x;
    world_from_camera.m[1][1] = new_up.y;
    world_from_camera.m[2][1] = new_up.z;
    world_from_camera.m[0][2] = dir.x;
    world_from_camera.m[1][2] = dir.y;
    world_from_camera.m[2][2] = dir.z;
    world_from_camera.m[0][3] = eye.x;
    world_from_camera.m[1][3] = eye.y;
    world_from_camera.m[2][3] = eye.z;
    mat4 inv;
    if (!mat4_inverse(world_from_camera, &inv))
        return false;
    *camera_from_world = (transform){inv, world_from_camera};
    return true;
}

transform transform_perspective(double fov_degrees, double n, double f)
{
    mat4 persp = mat4_identity();
    persp.m[2][2] = f / (f - n);
    persp.m[2][3] = -f * n / (f - n);
    persp.m[3][2] = 1.0;
    persp.m[3][3] = 0.0;
    transform p;
    bool ok = transform_from_matrix(persp, &p);
    (void)ok;
    double inv_tan = 1.0 / tan(hz_radians(fov_degrees) / 2.0);
    return transform_compose(transform_scale(v3(inv_tan, inv_tan, 1.0)), p);
}

transform transform_orthographic(double n, double f)
{
    return transform_compose(transform_scale(v3(1.0, 1.0, 1.0 / (f - n))),
                             transform_translate(v3(0.0, 0.0, -n)));
}

vec3 transform_point(const transform *t, vec3 p)
{
    const double(*m)[4] = t->m.m;
    double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
    double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
    double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
    double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
    return w == 1.0 ? v3(x, y, z) : v3(x / w, y / w, z / w);
}

void transform_box(const transform *t, vec3 lo, vec3 hi, vec3 *out_lo, vec3 *out_hi)
{
    for (int c = 0; c < 8; ++c) {
        vec3 p = transform_point(t, v3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y,
                                       c & 4 ? hi.z : lo.z));
        *out_lo = c == 0 ? p : v3(fmin(out_lo->x, p.x), fmin(out_lo->y, p.y), fmin(out_lo->z, p.z));
        *out_hi = c == 0 ? p : v3(fmax(out_hi->x, p.x), fmax(out_hi->y, p.y), fmax(out_hi->z, p.z));
    }
}

vec3 transform_vector(const transform *t, vec3 v)
{
    const double(*m)[4] = t->m.m;
    return v3(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
              m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
              m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z);
}

vec3 transform_normal(const transform *t, vec3 n)
{
    const double(*mi)[4] = t->m_inv.m;
    return v3(mi[0][0] * n.x + mi[1][0] * n.y + mi[2][0] * n.z,
              mi[0][1] * n.x + mi[1][1] * n.y + mi[2][1] * n.z,
              mi[0][2] * n.x + mi[1][2] * n.y + mi[2][2] * n.z);
}

double transform_det3(const transform *t)
{
    const double(*m)[4] = t->m.m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

bool transform_swaps_handedness(const transform *t) { return transform_det3(t) < 0.0; }
