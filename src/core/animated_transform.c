#include "core/animated_transform.h"

#include <math.h>

static double quat_dot(quat a, quat b) { return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w; }

static quat quat_scale(quat q, double s) { return (quat){q.x * s, q.y * s, q.z * s, q.w * s}; }

static quat quat_add(quat a, quat b) { return (quat){a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w}; }

static quat quat_normalize(quat q) { return quat_scale(q, 1.0 / sqrt(quat_dot(q, q))); }

mat4 quat_to_mat4(quat q)
{
    double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    double wx = q.x * q.w, wy = q.y * q.w, wz = q.z * q.w;
    mat4 m = mat4_identity();
    m.m[0][0] = 1 - 2 * (yy + zz);
    m.m[0][1] = 2 * (xy - wz);
    m.m[0][2] = 2 * (xz + wy);
    m.m[1][0] = 2 * (xy + wz);
    m.m[1][1] = 1 - 2 * (xx + zz);
    m.m[1][2] = 2 * (yz - wx);
    m.m[2][0] = 2 * (xz - wy);
    m.m[2][1] = 2 * (yz + wx);
    m.m[2][2] = 1 - 2 * (xx + yy);
    return m;
}

quat quat_from_mat4(const mat4 *r)
{
    const double(*m)[4] = r->m;
    double trace = m[0][0] + m[1][1] + m[2][2];
    quat q;
    if (trace > 0.0) {
        double s = sqrt(trace + 1.0) * 2.0; /* 4w */
        q.w = 0.25 * s;
        q.x = (m[2][1] - m[1][2]) / s;
        q.y = (m[0][2] - m[2][0]) / s;
        q.z = (m[1][0] - m[0][1]) / s;
    } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
        double s = sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2.0; /* 4x */
        q.w = (m[2][1] - m[1][2]) / s;
        q.x = 0.25 * s;
        q.y = (m[0][1] + m[1][0]) / s;
        q.z = (m[0][2] + m[2][0]) / s;
    } else if (m[1][1] > m[2][2]) {
        double s = sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2.0; /* 4y */
        q.w = (m[0][2] - m[2][0]) / s;
        q.x = (m[0][1] + m[1][0]) / s;
        q.y = 0.25 * s;
        q.z = (m[1][2] + m[2][1]) / s;
    } else {
        double s = sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2.0; /* 4z */
        q.w = (m[1][0] - m[0][1]) / s;
        q.x = (m[0][2] + m[2][0]) / s;
        q.y = (m[1][2] + m[2][1]) / s;
        q.z = 0.25 * s;
    }
    return quat_normalize(q);
}

static double safe_asin(double x) { return asin(fmin(1.0, fmax(-1.0, x))); }

/* sin(x)/x, exact at 0. */
static double sinc(double x) { return 1.0 - x * x == 1.0 ? 1.0 : sin(x) / x; }

quat quat_slerp(double t, quat a, quat b)
{
    /* pbrt-v4: the angle between the quaternions computed stably, and the
     * sin(x)/x form, so nearly equal rotations do not divide by ~0. */
    double theta;
    if (quat_dot(a, b) < 0.0) {
        quat s = quat_add(a, b);
        theta = HZ_PI - 2.0 * safe_asin(sqrt(quat_dot(s, s)) / 2.0);
    } else {
        quat d = quat_add(b, quat_scale(a, -1.0));
        theta = 2.0 * safe_asin(sqrt(quat_dot(d, d)) / 2.0);
    }
    double st = sinc(theta);
    quat q = quat_add(quat_scale(a, (1.0 - t) * sinc((1.0 - t) * theta) / st),
                      quat_scale(b, t * sinc(t * theta) / st));
    return quat_normalize(q);
}

static double det3(const mat4 *m)
{
    const double(*a)[4] = m->m;
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

void transform_decompose(const mat4 *m, vec3 *translation, quat *rotation, mat4 *scale)
{
    *translation = v3(m->m[0][3], m->m[1][3], m->m[2][3]);
    mat4 a = mat4_identity();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            a.m[i][j] = m->m[i][j];
    /* A reflection cannot be a rotation: take it out as -I (3D), into S. */
    double sign = det3(&a) < 0.0 ? -1.0 : 1.0;
    mat4 r = a;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] *= sign;
    /* Polar decomposition by averaging with the inverse transpose. */
    for (int iter = 0; iter < 100; ++iter) {
        mat4 rit;
        if (!mat4_inverse(mat4_transpose(r), &rit))
            break;
        double norm = 0.0;
        mat4 next = r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                next.m[i][j] = 0.5 * (r.m[i][j] + rit.m[i][j]);
                norm = fmax(norm, fabs(next.m[i][j] - r.m[i][j]));
            }
        r = next;
        if (norm < 1e-15)
            break;
    }
    *rotation = quat_from_mat4(&r);
    /* S = R^-1 A with the exact rotation of the quaternion, so T R S is A. */
    mat4 rq = quat_to_mat4(*rotation);
    *scale = mat4_mul(mat4_transpose(rq), a);
}

animated_transform animated_transform_static(transform t)
{
    animated_transform a = {0};
    a.start = a.end = t;
    a.start_time = 0.0;
    a.end_time = 1.0;
    a.animated = false;
    return a;
}

animated_transform animated_transform_make(transform start, double start_time, transform end,
                                           double end_time)
{
    animated_transform a = animated_transform_static(start);
    a.end = end;
    a.start_time = start_time;
    a.end_time = end_time;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (start.m.m[i][j] != end.m.m[i][j])
                a.animated = true;
    if (!(end_time > start_time))
        a.animated = false; /* no time span to move over: the start transform */
    if (!a.animated) {
        a.end = start;
        return a;
    }
    transform_decompose(&start.m, &a.translation[0], &a.rotation[0], &a.scale[0]);
    transform_decompose(&end.m, &a.translation[1], &a.rotation[1], &a.scale[1]);
    /* The shorter arc. */
    if (quat_dot(a.rotation[0], a.rotation[1]) < 0.0)
        a.rotation[1] = quat_scale(a.rotation[1], -1.0);
    return a;
}

transform animated_transform_at(const animated_transform *a, double time)
{
    if (!a->animated || time <= a->start_time)
        return a->start;
    if (time >= a->end_time)
        return a->end;
    double dt = (time - a->start_time) / (a->end_time - a->start_time);
    vec3 t = v3_add(v3_scale(a->translation[0], 1.0 - dt), v3_scale(a->translation[1], dt));
    mat4 r = quat_to_mat4(quat_slerp(dt, a->rotation[0], a->rotation[1]));
    mat4 s = mat4_identity();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            s.m[i][j] = (1.0 - dt) * a->scale[0].m[i][j] + dt * a->scale[1].m[i][j];
    mat4 m = mat4_mul(r, s);
    m.m[0][3] = t.x;
    m.m[1][3] = t.y;
    m.m[2][3] = t.z;
    transform out;
    if (!transform_from_matrix(m, &out))
        return a->start; /* a degenerate in-between scale: hold the start */
    return out;
}
