/* pbrt-v4's RealisticCamera, after its cameras.cpp: element tracing in lens
 * space (camera space with z negated), the thick-lens focus, exit-pupil
 * bounds and ray generation. Written for haze in double precision. */
#include "camera/realistic.h"

#include <math.h>
#include <stdlib.h>

#include "core/vec.h"

static double eta_or_air(double eta) { return eta != 0.0 ? eta : 1.0; }

static lens_ray mirror_z(lens_ray r)
{
    return (lens_ray){v3(r.o.x, r.o.y, -r.o.z), v3(r.d.x, r.d.y, -r.d.z)};
}

/* The regular pentagon (pbrt-v4's, scaled by 0.8) and five-pointed star;
 * y is mirrored as pbrt-v4's FlipY of the aperture image does. */
static void aperture_outline(realistic_lens *l)
{
    l->poly_count = 0;
    if (l->shape == APERTURE_PENTAGON) {
        double r5 = sqrt(5.0);
        double c1 = (r5 - 1.0) / 4.0, c2 = (r5 + 1.0) / 4.0;
        double s1 = sqrt(10.0 + 2.0 * r5) / 4.0, s2 = sqrt(10.0 - 2.0 * r5) / 4.0;
        const vec2 v[5] = {{0.0, 1.0}, {s1, c1}, {s2, -c2}, {-s2, -c2}, {-s1, c1}};
        for (int i = 0; i < 5; ++i)
            l->poly[i] = v2(0.8 * v[i].x, -0.8 * v[i].y);
        l->poly_count = 5;
    } else if (l->shape == APERTURE_STAR) {
        double inner = cos(hz_radians(72.0)) / cos(hz_radians(36.0));
        for (int i = 0; i < 10; ++i) {
            double r = (i & 1) ? 1.0 : inner;
            l->poly[i] = v2(r * cos(HZ_PI * i / 5.0), -r * sin(HZ_PI * i / 5.0));
        }
        l->poly_count = 10;
    }
    double area = 0.0;
    for (int i = 0; i < l->poly_count; ++i) {
        vec2 a = l->poly[i], b = l->poly[(i + 1) % l->poly_count];
        area += a.x * b.y - b.x * a.y;
    }
    area = fabs(area) / 2.0;
    switch (l->shape) {
    case APERTURE_CIRCLE: l->shape_scale = 1.0; break;
    case APERTURE_GAUSSIAN: l->shape_scale = 1.0 / (1.0 - 2.0 / exp(1.0)); break;
    case APERTURE_SQUARE: l->shape_scale = HZ_PI; break; /* side 1: area 1 */
    case APERTURE_PENTAGON:
    case APERTURE_STAR: l->shape_scale = HZ_PI / area; break;
    case APERTURE_IMAGE: l->shape_scale = 1.0; break; /* the values are scaled */
    }
}

static bool polygon_contains(const vec2 *v, int n, double x, double y)
{
    bool in = false;
    for (int i = 0, j = n - 1; i < n; j = i++)
        if ((v[i].y > y) != (v[j].y > y) &&
            x < (v[j].x - v[i].x) * (y - v[i].y) / (v[j].y - v[i].y) + v[i].x)
            in = !in;
    return in;
}

/* pbrt-v4's bilinear lookup at uv in [0, 1]^2 (texel centres at half
 * integers), black outside the image. */
static double image_bilerp(const aperture_image *im, double u, double v)
{
    double x = u * im->width - 0.5, y = v * im->height - 0.5;
    double fx = floor(x), fy = floor(y);
    double dx = x - fx, dy = y - fy, sum = 0.0;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            double xi = fx + i, yi = fy + j;
            if (xi < 0.0 || yi < 0.0 || xi >= im->width || yi >= im->height)
                continue;
            double w = (i ? dx : 1.0 - dx) * (j ? dy : 1.0 - dy);
            sum += w * im->values[(size_t)yi * (size_t)im->width + (size_t)xi];
        }
    return sum;
}

/* The stop's transmission at (x, y) in units of its radius. */
static double aperture_weight(const realistic_lens *l, double x, double y)
{
    double r2 = x * x + y * y;
    switch (l->shape) {
    case APERTURE_CIRCLE: return r2 <= 1.0 ? 1.0 : 0.0;
    case APERTURE_GAUSSIAN:
        return r2 < 1.0 ? l->shape_scale * (exp(-r2) - exp(-1.0)) : 0.0;
    case APERTURE_SQUARE: return fabs(x) < 0.5 && fabs(y) < 0.5 ? l->shape_scale : 0.0;
    case APERTURE_PENTAGON:
    case APERTURE_STAR:
        return polygon_contains(l->poly, l->poly_count, x, y) ? l->shape_scale : 0.0;
    case APERTURE_IMAGE: return image_bilerp(&l->image, (x + 1.0) / 2.0, (y + 1.0) / 2.0);
    }
    return 0.0;
}

void realistic_elements(const lens_table *t, double aperture_diameter_mm, aperture_shape shape,
                        double film_diagonal_mm, int xres, int yres, realistic_lens *out,
                        bool *clamped)
{
    *clamped = false;
    out->count = t->count;
    for (int i = 0; i < t->count; ++i) {
        const lens_row *r = &t->rows[i];
        double diameter = r->aperture;
        if (r->radius == 0.0) {
            if (aperture_diameter_mm > diameter)
                *clamped = true;
            else
                diameter = aperture_diameter_mm;
        }
        out->e[i] = (lens_interface){r->radius / 1000.0, r->thickness / 1000.0, r->eta,
                                     diameter / 2000.0};
    }
    out->shape = shape;
    out->image = (aperture_image){0, 0, NULL};
    aperture_outline(out);
    /* pbrt-v4's physical extent: the film's diagonal at its aspect ratio. */
    double aspect = (double)yres / (double)xres;
    out->film_diagonal = film_diagonal_mm / 1000.0;
    double x = sqrt(out->film_diagonal * out->film_diagonal / (1.0 + aspect * aspect));
    out->film_half[0] = x / 2.0;
    out->film_half[1] = aspect * x / 2.0;
    for (int i = 0; i < REALISTIC_PUPIL_INTERVALS; ++i) {
        out->pupil[i][0] = out->pupil[i][2] = INFINITY;
        out->pupil[i][1] = out->pupil[i][3] = -INFINITY;
    }
}

hz_status realistic_set_aperture_image(realistic_lens *l, int width, int height, float *values,
                                       hz_error *err)
{
    size_t n = (size_t)width * (size_t)height;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        if (!(values[i] >= 0.0f) || !isfinite(values[i])) {
            free(values);
            return hz_fail(err, "the aperture image has a negative or non-finite value at "
                                "texel (%zu, %zu)",
                           i % (size_t)width, i / (size_t)width);
        }
        sum += values[i];
    }
    if (!(n > 0 && sum > 0.0)) {
        free(values);
        return hz_fail(err, "the aperture image is black: no light passes the stop");
    }
    double scale = (HZ_PI / 4.0) / (sum / (double)n);
    for (int y = 0; y < height / 2; ++y)
        for (int x = 0; x < width; ++x) {
            float *a = &values[(size_t)y * (size_t)width + (size_t)x];
            float *b = &values[(size_t)(height - 1 - y) * (size_t)width + (size_t)x];
            float t = *a;
            *a = *b;
            *b = t;
        }
    for (size_t i = 0; i < n; ++i)
        values[i] = (float)(values[i] * scale);
    realistic_lens_free(l);
    l->image = (aperture_image){width, height, values};
    l->shape = APERTURE_IMAGE;
    aperture_outline(l);
    return HZ_OK;
}

void realistic_lens_free(realistic_lens *l)
{
    free(l->image.values);
    l->image = (aperture_image){0, 0, NULL};
    if (l->shape == APERTURE_IMAGE) {
        l->shape = APERTURE_CIRCLE;
        aperture_outline(l);
    }
}

double realistic_rear_z(const realistic_lens *l) { return l->e[l->count - 1].thickness; }

double realistic_front_z(const realistic_lens *l)
{
    double z = 0.0;
    for (int i = 0; i < l->count; ++i)
        z += l->e[i].thickness;
    return z;
}

/* The ray (lens space) meets the sphere of `radius` centred on the axis at
 * z_center: the crossing pbrt-v4 picks by the ray's direction and the
 * element's curvature, with the normal facing back along the ray. */
static bool intersect_element(double radius, double z_center, lens_ray r, double *t, vec3 *n)
{
    vec3 o = v3(r.o.x, r.o.y, r.o.z - z_center);
    double a = v3_dot(r.d, r.d), b = 2.0 * v3_dot(r.d, o), c = v3_dot(o, o) - radius * radius;
    double disc = b * b - 4.0 * a * c;
    if (!(disc >= 0.0) || a == 0.0)
        return false;
    double q = -0.5 * (b < 0.0 ? b - sqrt(disc) : b + sqrt(disc));
    double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
    if (t0 > t1) {
        double s = t0;
        t0 = t1;
        t1 = s;
    }
    bool closer = (r.d.z > 0.0) ^ (radius < 0.0);
    *t = closer ? t0 : t1;
    if (!(*t >= 0.0))
        return false;
    *n = v3_normalize(v3_add(o, v3_scale(r.d, *t)));
    if (v3_dot(*n, r.d) > 0.0)
        *n = v3_neg(*n);
    return true;
}

/* Snell's law for unit wi (pointing away from the surface) and relative
 * index eta = eta_t / eta_i; false at total internal reflection. */
static bool refract(vec3 wi, vec3 n, double eta, vec3 *wt)
{
    double cos_i = v3_dot(n, wi);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = v3_neg(n);
    }
    double sin2_t = fmax(0.0, 1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0)
        return false;
    double cos_t = sqrt(1.0 - sin2_t);
    *wt = v3_add(v3_scale(wi, -1.0 / eta), v3_scale(n, cos_i / eta - cos_t));
    return true;
}

/* One interface at lens-space z: moves r to the hit; refracts from index
 * eta_i into eta_t unless it is the stop. The aperture weight (1 off the
 * stop or for `shaped` false), 0 when blocked. */
static double cross_interface(const realistic_lens *l, const lens_interface *e, double z,
                              double eta_i, double eta_t, bool shaped, lens_ray *r)
{
    double t;
    vec3 n = v3(0.0, 0.0, 0.0);
    bool stop = e->radius == 0.0;
    if (stop) {
        t = (z - r->o.z) / r->d.z;
        if (!(t >= 0.0) || !isfinite(t))
            return 0.0;
    } else if (!intersect_element(e->radius, z + e->radius, *r, &t, &n)) {
        return 0.0;
    }
    vec3 p = v3_add(r->o, v3_scale(r->d, t));
    double weight = 1.0;
    if (stop && shaped && l->shape != APERTURE_CIRCLE) {
        weight = aperture_weight(l, p.x / e->aperture_radius, p.y / e->aperture_radius);
    } else if (p.x * p.x + p.y * p.y > e->aperture_radius * e->aperture_radius) {
        weight = 0.0;
    }
    if (weight == 0.0)
        return 0.0;
    r->o = p;
    if (!stop && !refract(v3_neg(v3_normalize(r->d)), n, eta_t / eta_i, &r->d))
        return 0.0;
    return weight;
}

double realistic_trace_from_film(const realistic_lens *l, lens_ray in, lens_ray *out)
{
    lens_ray r = mirror_z(in);
    double z = 0.0, weight = 1.0;
    for (int i = l->count - 1; i >= 0; --i) {
        const lens_interface *e = &l->e[i];
        z -= e->thickness;
        double eta_t = i > 0 ? eta_or_air(l->e[i - 1].eta) : 1.0;
        double w = cross_interface(l, e, z, eta_or_air(e->eta), eta_t, true, &r);
        if (w == 0.0)
            return 0.0;
        if (e->radius == 0.0)
            weight = w;
    }
    if (out)
        *out = mirror_z(r);
    return weight;
}

bool realistic_trace_from_scene(const realistic_lens *l, lens_ray in, lens_ray *out)
{
    lens_ray r = mirror_z(in);
    double z = -realistic_front_z(l);
    for (int i = 0; i < l->count; ++i) {
        const lens_interface *e = &l->e[i];
        double eta_i = i == 0 ? 1.0 : eta_or_air(l->e[i - 1].eta);
        if (cross_interface(l, e, z, eta_i, eta_or_air(e->eta), false, &r) == 0.0)
            return false;
        z += e->thickness;
    }
    if (out)
        *out = mirror_z(r);
    return true;
}

/* pbrt-v4's ComputeCardinalPoints: where the exiting ray crosses the axis
 * (the focal point) and the height of the entering one (the principal
 * plane), as lens-space z. */
static void cardinal_points(lens_ray in, lens_ray out, double *pz, double *fz)
{
    double tf = -out.o.x / out.d.x;
    *fz = -(out.o.z + tf * out.d.z);
    double tp = (in.o.x - out.o.x) / out.d.x;
    *pz = -(out.o.z + tp * out.d.z);
}

hz_status realistic_thick_lens(const realistic_lens *l, double pz[2], double fz[2],
                               hz_error *err)
{
    double x = 0.001 * l->film_diagonal;
    lens_ray scene = {v3(x, 0.0, realistic_front_z(l) + 1.0), v3(0.0, 0.0, -1.0)}, film;
    if (!realistic_trace_from_scene(l, scene, &film) || film.d.x == 0.0)
        return hz_fail(err, "a ray parallel to the axis from the scene does not reach the film "
                            "through the lens system (is the aperture stop too small?)");
    cardinal_points(scene, film, &pz[0], &fz[0]);
    film = (lens_ray){v3(x, 0.0, realistic_rear_z(l) - 1.0), v3(0.0, 0.0, 1.0)};
    if (realistic_trace_from_film(l, film, &scene) == 0.0 || scene.d.x == 0.0)
        return hz_fail(err, "a ray parallel to the axis from the film does not leave the lens "
                            "system (is the aperture stop too small?)");
    cardinal_points(film, scene, &pz[1], &fz[1]);
    return HZ_OK;
}

hz_status realistic_focus(realistic_lens *l, double focus_distance, hz_error *err)
{
    double pz[2] = {0.0, 0.0}, fz[2] = {0.0, 0.0};
    if (realistic_thick_lens(l, pz, fz, err) != HZ_OK)
        return HZ_ERROR;
    double f = fz[0] - pz[0], z = -focus_distance;
    double c = (pz[1] - z - pz[0]) * (pz[1] - z - 4.0 * f - pz[0]);
    if (!(c > 0.0) || !isfinite(c))
        return hz_fail(err, "\"focusdistance\" %g is too short for this lens system (its "
                            "effective focal length is %g)",
                       focus_distance, f);
    double delta = (pz[1] - z + pz[0] - sqrt(c)) / 2.0;
    double film = l->e[l->count - 1].thickness + delta;
    if (!(film > 0.0) || !isfinite(film))
        return hz_fail(err, "focusing at %g puts the film at %g, not behind the rear element",
                       focus_distance, film);
    l->e[l->count - 1].thickness = film;
    return HZ_OK;
}

static double radical_inverse(unsigned base, unsigned long long i)
{
    double inv = 1.0 / base, f = inv, r = 0.0;
    for (; i; i /= base, f *= inv)
        r += (double)(i % base) * f;
    return r;
}

/* The rear-element point (px, py) of the bounds' frame for a film point at
 * radius r and angle phi: the frame in which that film point lies on +x, as
 * realistic_generate rotates its samples. */
static lens_ray pupil_ray(double r, double phi, double px, double py, double rz)
{
    double c = cos(phi), s = sin(phi);
    vec3 p_film = v3(r * c, r * s, 0.0);
    return (lens_ray){p_film, v3_sub(v3(c * px - s * py, s * px + c * py, rz), p_film)};
}

/* pbrt-v4's BoundExitPupil for film radii [x0, x1]. pbrt-v4 traces film
 * points on +x only and rotates the bounds to each film point's angle, which
 * holds for a round stop; a square, pentagon, star or image stop breaks the
 * symmetry, so there the film points also take every angle (phi from a third
 * Halton dimension) and the bounds hold the pupil at any angle. */
static void bound_interval(const realistic_lens *l, double x0, double x1, int samples,
                           double b[4])
{
    double rear = l->e[l->count - 1].aperture_radius, rz = realistic_rear_z(l);
    bool any_angle = l->shape != APERTURE_CIRCLE && l->shape != APERTURE_GAUSSIAN;
    b[0] = b[2] = INFINITY;
    b[1] = b[3] = -INFINITY;
    for (int i = 0; i < samples; ++i) {
        double r = hz_lerp((i + 0.5) / samples, x0, x1);
        double phi = any_angle ? 2.0 * HZ_PI * radical_inverse(5, (unsigned long long)i) : 0.0;
        double px = hz_lerp(radical_inverse(2, (unsigned long long)i), -1.5 * rear, 1.5 * rear);
        double py = hz_lerp(radical_inverse(3, (unsigned long long)i), -1.5 * rear, 1.5 * rear);
        if (px >= b[0] && px <= b[1] && py >= b[2] && py <= b[3])
            continue;
        if (realistic_trace_from_film(l, pupil_ray(r, phi, px, py, rz), NULL) == 0.0)
            continue;
        b[0] = fmin(b[0], px);
        b[1] = fmax(b[1], px);
        b[2] = fmin(b[2], py);
        b[3] = fmax(b[3], py);
    }
    if (b[0] > b[1] || b[2] > b[3])
        return;
    /* The sample spacing: twice the sampled square's diagonal over sqrt(n). */
    double grow = 2.0 * (3.0 * rear * sqrt(2.0)) / sqrt((double)samples);
    b[0] -= grow;
    b[1] += grow;
    b[2] -= grow;
    b[3] += grow;
}

void realistic_bound_pupil(realistic_lens *l, int samples)
{
    double half = l->film_diagonal / 2.0;
    for (int i = 0; i < REALISTIC_PUPIL_INTERVALS; ++i)
        bound_interval(l, (double)i / REALISTIC_PUPIL_INTERVALS * half,
                       (double)(i + 1) / REALISTIC_PUPIL_INTERVALS * half, samples, l->pupil[i]);
}

double realistic_generate(const realistic_lens *l, vec2 p, vec2 u, int xres, int yres,
                          lens_ray *out)
{
    double fx = hz_lerp(p.x / xres, -l->film_half[0], l->film_half[0]);
    double fy = hz_lerp(p.y / yres, -l->film_half[1], l->film_half[1]);
    vec3 p_film = v3(-fx, fy, 0.0);
    /* pbrt-v4's SampleExitPupil: the bounds for this film radius, rotated
     * from the +x axis to the film point's angle. */
    double r_film = sqrt(p_film.x * p_film.x + p_film.y * p_film.y);
    double k = r_film / (l->film_diagonal / 2.0) * REALISTIC_PUPIL_INTERVALS;
    int idx = k < REALISTIC_PUPIL_INTERVALS - 1 ? (int)k : REALISTIC_PUPIL_INTERVALS - 1;
    const double *b = l->pupil[idx];
    if (!(b[0] <= b[1] && b[2] <= b[3]))
        return 0.0;
    double lx = hz_lerp(u.x, b[0], b[1]), ly = hz_lerp(u.y, b[2], b[3]);
    double area = (b[1] - b[0]) * (b[3] - b[2]);
    double sin_t = r_film != 0.0 ? p_film.y / r_film : 0.0;
    double cos_t = r_film != 0.0 ? p_film.x / r_film : 1.0;
    vec3 p_pupil = v3(cos_t * lx - sin_t * ly, sin_t * lx + cos_t * ly, realistic_rear_z(l));
    lens_ray r = {p_film, v3_sub(p_pupil, p_film)};
    double weight = realistic_trace_from_film(l, r, out);
    if (weight == 0.0)
        return 0.0;
    double c = v3_normalize(r.d).z, rz = realistic_rear_z(l);
    return weight * (c * c) * (c * c) * area / (rz * rz);
}
