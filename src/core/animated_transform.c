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

/* ---- Embree's quaternion motion ---- */

static bool is_affine(const mat4 *m)
{
    return m->m[3][0] == 0.0 && m->m[3][1] == 0.0 && m->m[3][2] == 0.0 && m->m[3][3] == 1.0;
}

bool transform_decompose_qr(const mat4 *m, quat_decomposition *out)
{
    if (!is_affine(m))
        return false;
    vec3 a0 = v3(m->m[0][0], m->m[1][0], m->m[2][0]);
    vec3 a1 = v3(m->m[0][1], m->m[1][1], m->m[2][1]);
    vec3 a2 = v3(m->m[0][2], m->m[1][2], m->m[2][2]);
    /* Gram-Schmidt on the columns (modified: each projection from the
     * updated vector); the third axis is the cross product, so Q is a
     * rotation and U22 takes the determinant's sign. */
    double u00 = v3_length(a0);
    if (!(u00 > 0.0) || !isfinite(u00))
        return false;
    vec3 q0 = v3_scale(a0, 1.0 / u00);
    double u01 = v3_dot(q0, a1);
    vec3 r1 = v3_sub(a1, v3_scale(q0, u01));
    double u11 = v3_length(r1);
    if (!(u11 > 0.0) || !isfinite(u11))
        return false;
    vec3 q1 = v3_scale(r1, 1.0 / u11);
    vec3 q2 = v3_normalize(v3_cross(q0, q1));
    double u02 = v3_dot(q0, a2);
    vec3 r2 = v3_sub(a2, v3_scale(q0, u02));
    double u12 = v3_dot(q1, r2);
    r2 = v3_sub(r2, v3_scale(q1, u12));
    double u22 = v3_dot(q2, r2);
    if (!(u22 != 0.0) || !isfinite(u22))
        return false;
    mat4 q = mat4_identity();
    vec3 cols[3] = {q0, q1, q2};
    for (int c = 0; c < 3; ++c) {
        q.m[0][c] = cols[c].x;
        q.m[1][c] = cols[c].y;
        q.m[2][c] = cols[c].z;
    }
    out->rotation = quat_from_mat4(&q);
    out->scale[0] = u00;
    out->scale[1] = u11;
    out->scale[2] = u22;
    out->skew[0] = u01;
    out->skew[1] = u02;
    out->skew[2] = u12;
    out->translation = v3(m->m[0][3], m->m[1][3], m->m[2][3]);
    return true;
}

static mat4 trs_matrix(vec3 t, quat r, const double scale[3], const double skew[3])
{
    mat4 u = mat4_identity();
    u.m[0][0] = scale[0];
    u.m[1][1] = scale[1];
    u.m[2][2] = scale[2];
    u.m[0][1] = skew[0];
    u.m[0][2] = skew[1];
    u.m[1][2] = skew[2];
    mat4 m = mat4_mul(quat_to_mat4(r), u);
    m.m[0][3] = t.x;
    m.m[1][3] = t.y;
    m.m[2][3] = t.z;
    return m;
}

mat4 quat_decomposition_matrix(const quat_decomposition *d)
{
    return trs_matrix(d->translation, d->rotation, d->scale, d->skew);
}

/* Embree 3's slerp (common/math/quaternion.h), in double: the shorter arc,
 * and a normalised lerp above cos 0.9995. */
static quat embree_slerp(quat q0, quat q1, double t)
{
    double c = quat_dot(q0, q1);
    if (c < 0.0) {
        q1 = quat_scale(q1, -1.0);
        c = -c;
    }
    if (c > 0.9995)
        return quat_normalize(quat_add(quat_scale(q0, 1.0 - t), quat_scale(q1, t)));
    double phi = t * acos(c);
    quat perp = quat_normalize(quat_add(q1, quat_scale(q0, -c)));
    return quat_add(quat_scale(q0, cos(phi)), quat_scale(perp, sin(phi)));
}

mat4 quat_decomposition_interpolate(const quat_decomposition *a, const quat_decomposition *b,
                                    double u)
{
    double scale[3], skew[3];
    for (int i = 0; i < 3; ++i) {
        scale[i] = (1.0 - u) * a->scale[i] + u * b->scale[i];
        skew[i] = (1.0 - u) * a->skew[i] + u * b->skew[i];
    }
    vec3 t = v3_add(v3_scale(a->translation, 1.0 - u), v3_scale(b->translation, u));
    return trs_matrix(t, embree_slerp(a->rotation, b->rotation, u), scale, skew);
}

bool animated_transform_time_steps(const animated_transform *a, int segments,
                                   quat_decomposition *steps)
{
    for (int i = 0; i <= segments; ++i) {
        double time = i == segments ? a->end_time
                                    : hz_lerp((double)i / segments, a->start_time, a->end_time);
        transform x = animated_transform_at(a, time);
        if (!transform_decompose_qr(&x.m, &steps[i]))
            return false;
        if (i > 0 && quat_dot(steps[i - 1].rotation, steps[i].rotation) < 0.0)
            steps[i].rotation = quat_scale(steps[i].rotation, -1.0);
    }
    return true;
}

mat4 quat_motion_at(const quat_decomposition *steps, int segments, double u)
{
    /* Embree's getTimeSegment */
    double scaled = u * segments;
    double seg = fmin(fmax(floor(scaled), 0.0), segments - 1.0);
    int i = (int)seg;
    return quat_decomposition_interpolate(&steps[i], &steps[i + 1], scaled - seg);
}

double animated_transform_steps_error(const animated_transform *a,
                                      const quat_decomposition *steps, int segments, vec3 lo,
                                      vec3 hi)
{
    double worst = 0.0, size = 0.0;
    for (int i = 0; i < segments; ++i)
        for (int k = 1; k <= 3; ++k) {
            double u = (i + 0.25 * k) / segments;
            transform want = animated_transform_at(a, hz_lerp(u, a->start_time, a->end_time));
            mat4 got = quat_motion_at(steps, segments, u);
            transform gt = {got, got}; /* only the forward matrix is used */
            for (int c = 0; c < 8; ++c) {
                vec3 p = v3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
                vec3 pw = transform_point(&want, p);
                worst = fmax(worst, v3_length(v3_sub(transform_point(&gt, p), pw)));
                size = fmax(size, v3_length(pw));
            }
        }
    return size > 0.0 ? worst / size : worst;
}
