#define _POSIX_C_SOURCE 200809L
/* Analytic checks of haze's single-scattering media: scenes whose radiance has
 * a closed form (Beer–Lambert, airlight) or that must agree with each other
 * (a constant-density grid against a homogeneous box, the three transmittance
 * estimators), evaluated through render_scene_li for the camera ray through
 * pixel centres. Set HAZE_MEDIA_VERBOSE=1 to print the measured errors. */
#include "media_test_util.h"
#include "cli_util.h"

#include "geometry/geometry.h" /* GEOMETRY_SHADOW_EPSILON */

/* ---- 1. Beer–Lambert, homogeneous ------------------------------------------ */

static const rgb ink_sigma = {0.5 * 0.8, 1.0 * 0.8, 2.0 * 0.8, 1.0 * 0.8}; /* sigma_a times scale */
static const rgb emit_L = {2, 3, 4, 3};

/* An emitting 40x40 quad at z = -3 (both sides), a purely absorbing medium
 * "ink" (sigma_a [0.5 1 2], scale 0.8), and `shapes`. */
static char *ink_scene(const char *camera, const char *shapes)
{
    return sfmt("%s"
                "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                "Sampler \"independent\" \"integer pixelsamples\" 1\n"
                "Integrator \"singlescatter\"\n"
                "WorldBegin\n"
                "MediumInterface \"\" \"\"\n"
                "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" "
                "\"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0 0 0] \"float scale\" 0.8\n"
                "AttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                "AreaLightSource \"diffuse\" \"rgb L\" [2 3 4] \"bool twosided\" true\n"
                "Shape \"trianglemesh\" \"point3 P\" [-20 -20 -3  20 -20 -3  20 20 -3  -20 20 -3]\n"
                "  \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n"
                "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n%s"
                "AttributeEnd\n",
                camera, shapes);
}

/* Length of o + t d (unit d, t > 0) inside the sphere |p| < R; *grazing when
 * the ray passes so close to the rim that the chord is ill-conditioned. */
static double sphere_path(vec3 o, vec3 d, double R, bool *grazing)
{
    double b = v3_dot(o, d);
    double disc = b * b - (v3_length_sq(o) - R * R);
    *grazing = fabs(disc) < 1e-4 * R * R;
    if (disc <= 0.0)
        return 0.0;
    double q = sqrt(disc);
    double t0 = fmax(-b - q, 0.0), t1 = -b + q;
    return t1 > t0 ? t1 - t0 : 0.0;
}

/* Every pixel of the ink scene: exp(-σ_t·d)·L_e, d from `path`, within 1e-5. */
static int check_ink(const char *camera, const char *shapes, double R, double slab_half,
                     int *through)
{
    char *text = ink_scene(camera, shapes);
    render_scene *rs = build(text);
    int checked = 0;
    double worst = 0.0, dpath = 0.0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            vec3 o, d;
            camera_ray_world(rs, x + 0.5, y + 0.5, &o, &d);
            bool grazing = false;
            double len;
            if (R > 0.0) {
                len = sphere_path(o, d, R, &grazing);
            } else { /* slab |z| < slab_half, unbounded in x and y (within the quad) */
                double z0 = o.z, dz = d.z;
                double ta = (-slab_half - z0) / dz, tb = (slab_half - z0) / dz;
                double t0 = fmax(fmin(ta, tb), 0.0), t1 = fmax(ta, tb);
                len = t1 > t0 ? t1 - t0 : 0.0;
            }
            if (grazing)
                continue;
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            rgb want =
                rgb_make(emit_L.r * exp(-ink_sigma.r * len), emit_L.g * exp(-ink_sigma.g * len),
                         emit_L.b * exp(-ink_sigma.b * len));
            for (int c = 0; c < 3; ++c)
                worst = fmax(worst, fabs(ch(e.L, c) / ch(want, c) - 1.0));
            /* the path length the renderer attenuated over, minus the true one */
            dpath = fmax(dpath, fabs(log(e.L.b / want.b) / ink_sigma.b));
            expect_rgb_close(e.L, want, 1e-5, 0, "Beer-Lambert", x, y);
            *through += len > 0.0;
            ++checked;
        }
    note("beer-lambert %s %g: worst relative error %.3g over %d pixels (path length error "
         "%.3g)\n",
         R > 0.0 ? "sphere radius" : "slab half-thickness", R > 0.0 ? R : slab_half, worst, checked,
         dpath);
    render_scene_destroy(rs);
    free(text);
    return checked;
}

static void test_beer_lambert_homogeneous(void **state)
{
    (void)state;
    const char *outside = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n";
    int through = 0;
    /* Two sphere sizes (chords up to 1 and 2.4), then a slab |z| < 0.25 made of
     * a closed box mesh. */
    assert_true(check_ink(outside, "Shape \"sphere\" \"float radius\" 0.5\n", 0.5, 0, &through) >
                200);
    assert_true(through > 20);
    through = 0;
    assert_true(check_ink(outside, "Shape \"sphere\" \"float radius\" 1.2\n", 1.2, 0, &through) >
                200);
    assert_true(through > 150 && through < 256); /* the corners miss the sphere */
    char *slab = box_mesh(v3(-19, -19, -0.25), v3(19, 19, 0.25));
    through = 0;
    check_ink(outside, slab, 0, 0.25, &through);
    assert_int_equal(through, 256);

    /* The camera inside the medium: the sphere of radius 1.5 around it, and the
     * slab |z| < 0.25 with the camera at z = 0.1; only the path to the boundary
     * attenuates. */
    const char *inside = "LookAt 0.2 -0.1 0.5  0 0 -1  0 1 0\n"
                         "MediumInterface \"\" \"ink\"\n"
                         "Camera \"perspective\" \"float fov\" 60\n";
    through = 0;
    check_ink(inside, "Shape \"sphere\" \"float radius\" 1.5\n", 1.5, 0, &through);
    assert_int_equal(through, 256);
    const char *inside_slab = "LookAt 0.2 -0.1 0.1  0 0 -1  0 1 0\n"
                              "MediumInterface \"\" \"ink\"\n"
                              "Camera \"perspective\" \"float fov\" 60\n";
    through = 0;
    check_ink(inside_slab, slab, 0, 0.25, &through);
    assert_int_equal(through, 256);
    free(slab);
}

/* ---- 2. Beer–Lambert through box.vdb ----------------------------------------- */

/* volumes/box.vdb: density exactly 1 on index voxels [0,31]^3, voxel size 1/32,
 * index i at world i/32 (haze info: world bounds [-0.5, 31.5]/32). The field is
 * trilinear, so it is the product f(x) f(y) f(z) of hat-clamped ramps,
 * f(u) = clamp(min(u + 1, 32 - u), 0, 1) in index units: 1 on [0, 31], linear
 * to 0 at -1 and 32. Its integral across the box along an axis is therefore
 * 31 + 1/2 + 1/2 = 32 voxels = 1 world unit, and along a ray with direction
 * cosine c to the z axis that stays in x, y ∈ [0, 31], ∫ density dt = 1 / c.
 * So T = exp(-σ_t / c). */

/* Looking down the z axis through the middle (fov 8: every ray keeps x, y in
 * [6, 25] voxels), or tilted by 30° about y (fov 2, through the centre: x
 * runs over [6, 25] while z crosses the box). */
static const char *box_axis_view = "LookAt 0.484375 0.484375 4  0.484375 0.484375 0  0 1 0\n"
                                   "Camera \"perspective\" \"float fov\" 8\n";
static const char *box_tilted_view = "LookAt 2.484375 0.484375 3.948476  "
                                     "0.484375 0.484375 0.484375  0 1 0\n"
                                     "Camera \"perspective\" \"float fov\" 2\n";

static char *box_file_scene(const char *file, const char *view, const char *integrator,
                            const char *sampler)
{
    char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
    char *s = sfmt("%s"
                   "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                   "%s\n%s\n"
                   "WorldBegin\n"
                   "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                   "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                   "\"string filename\" \"%s/%s\" "
                   "\"rgb sigma_a\" [0.5 1 2] \"rgb sigma_s\" [0 0 0]\n"
                   "AttributeBegin\nMediumInterface \"box\" \"\"\nMaterial \"interface\"\n%s"
                   "AttributeEnd\n",
                   view, sampler, integrator, VOLUMES, file, encl);
    free(encl);
    return s;
}

static const rgb box_sigma = {0.5, 1.0, 2.0, 1.0};

/* Every pixel of an unbiased estimator's image of `file` (looked at along
 * z, where its optical depth is sigma * depth / c) within 4.5 standard
 * errors of exp(-tau), and so the sum over all pixels. */
static void check_box_transmittance(const char *file, double depth, const char *integrator,
                                    const char *mode, int spp)
{
    char *text = box_file_scene(file, box_axis_view, integrator,
                                "Sampler \"independent\" \"integer pixelsamples\" 16 "
                                "\"integer seed\" 7");
    render_scene *rs = build(text);
    pstat *px = image_stats(rs, 8, 8, spp);
    uint64_t lookups = 0;
    for (int i = 0; i < 64; ++i)
        lookups += px[i].lookups;
    double zmax = 0.0, dsum[3] = {0, 0, 0}, vsum[3] = {0, 0, 0}, relmax = 0.0;
    for (int i = 0; i < 64; ++i) {
        vec3 o, d;
        camera_ray_world(rs, i % 8 + 0.5, i / 8 + 0.5, &o, &d);
        double c = fabs(d.z);
        for (int k = 0; k < 3; ++k) {
            double want = exp(-ch(box_sigma, k) * depth / c);
            double got = ch(px[i].mean, k), se = ch(px[i].se, k);
            assert_true(se > 0.0 || !strcmp(mode, "residual")); /* stochastic */
            double z = (got - want) / se;
            zmax = fmax(zmax, fabs(z));
            relmax = fmax(relmax, fabs(got / want - 1.0));
            dsum[k] += got - want;
            vsum[k] += se * se;
            if (fabs(z) > 4.5) {
                print_error("%s tracking pixel %d channel %d: %.6g, want %.6g (se %.3g)\n", mode, i,
                            k, got, want, se);
                fail();
            }
        }
    }
    for (int k = 0; k < 3; ++k) {
        double z = dsum[k] / sqrt(vsum[k]);
        note("box.vdb %s: channel %d pooled z %.2f\n", mode, k, z);
        assert_true(fabs(z) < 4.5);
    }
    note("%s %s: max |z| %.2f, max relative error %.3g, %.1f lookups per sample\n", file, mode,
         zmax, relmax, (double)lookups / (64.0 * spp));
    free(px);
    render_scene_destroy(rs);
    free(text);
}

static void check_beer_lambert_box_vdb_tracking(const char *mode)
{
    /* Ratio tracking is unbiased: every pixel's mean over 4096 independent
     * samples must lie within 4.5 standard errors (estimated from the same
     * samples) of exp(-τ), and so must the sum over all pixels. */
    char *integrator = sfmt("Integrator \"singlescatter\" \"string transmittance\" \"%s\"", mode);
    check_box_transmittance("box.vdb", 1.0, integrator, mode, 4096);
    free(integrator);
}

/* Residual ratio tracking: box.vdb's inner cells are exactly constant, so
 * the control is exact there and only the boundary cells need collisions. */
static void test_beer_lambert_box_vdb_ratio(void **state)
{
    (void)state;
    check_beer_lambert_box_vdb_tracking("ratio");
    check_beer_lambert_box_vdb_tracking("residual");
}

/* One raymarched image of `file` (optical depth along z: sigma * depth / c,
 * `kinks` kinks of its trilinear field): every pixel's optical depth within
 * the bound; returns the largest |Δτ| and its largest fraction of the bound. */
static void check_raymarch_file(const char *file, double depth, int kinks, const char *view,
                                double h, double *worst, double *worst_frac)
{
    char integ[128];
    snprintf(integ, sizeof integ,
             "Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" "
             "\"float stepsize\" %g",
             h);
    char *text =
        box_file_scene(file, view, integ, "Sampler \"independent\" \"integer pixelsamples\" 1");
    render_scene *rs = build(text);
    *worst = *worst_frac = 0.0;
    for (int i = 0; i < 64; ++i) {
        vec3 o, d;
        camera_ray_world(rs, i % 8 + 0.5, i / 8 + 0.5, &o, &d);
        double c = fabs(d.z);
        pixel_eval e = eval_pixel(rs, i % 8 + 0.5, i / 8 + 0.5, 1);
        for (int k = 0; k < 3; ++k) {
            double tau = ch(box_sigma, k) * depth / c;
            double bound = kinks * ch(box_sigma, k) * c * h * h / 256.0;
            double err = fabs(-log(ch(e.L, k)) - tau);
            *worst = fmax(*worst, err);
            *worst_frac = fmax(*worst_frac, err / bound);
            if (!(err <= bound + 1e-9)) {
                print_error("raymarch h=%g pixel %d channel %d: tau %.9g, want %.9g "
                            "(bound %.3g)\n",
                            h, i, k, -log(ch(e.L, k)), tau, bound);
                fail();
            }
        }
    }
    render_scene_destroy(rs);
    free(text);
}

static void check_raymarch(const char *view, double h, double *worst, double *worst_frac)
{
    check_raymarch_file("box.vdb", 1.0, 4, view, h, worst, worst_frac);
}

static void test_beer_lambert_box_vdb_raymarch(void **state)
{
    (void)state;
    /* Fixed-step marching takes the density at stratum midpoints (strata of
     * dt <= h voxels from the support's entry). The midpoint rule is exact on
     * linear pieces; each of the 4 kinks of f(z) along the ray (slope change c
     * per voxel of ray) contributes at most c·dt²/8 voxels of error, so
     *   |Δτ| <= σ_t · c · h² / 2 voxels = σ_t · c · h² / 64 (world units),
     * 0.031 for h = 1 and σ_t = 2. Measured (σ_t = 2): along the axis the
     * kinks fall within ~0.03 voxel of strata ends (the support is 33/c voxels
     * long, cut into ceil(33/c) strata), |Δτ| = 5e-5 (h = 1) and 4e-6
     * (h = 0.25); tilted by 30° they fall anywhere, |Δτ| = 1.7e-3 (6% of the
     * bound) and 5.3e-4 (31% of the bound). */
    const char *views[2] = {box_axis_view, box_tilted_view};
    const double steps[2] = {1.0, 0.25};
    for (int v = 0; v < 2; ++v)
        for (int si = 0; si < 2; ++si) {
            double worst, frac;
            check_raymarch(views[v], steps[si], &worst, &frac);
            note("box.vdb raymarch %s h=%g: worst |dtau| %.3g (%.2f of the bound)\n",
                 v ? "tilted" : "axis", steps[si], worst, frac);
        }
}

/* volumes/box_inactive.vdb: box.vdb with the slab z in [12, 19] voxels
 * inactive and holding 50. Inactive voxels hold the background (haze's rule,
 * applied when the grid is loaded), so along z the box's optical depth is
 * that of 24 voxels of density 1, 0.75 world units, for every estimator:
 * before the rule, lookups read 50 in the slab while the majorants (from the
 * active voxels) bounded 1, and the estimators disagreed (ratio tracking
 * 0.954 where volpath gave 0.958, marching 0.762). */
static void test_inactive_voxels_are_background(void **state)
{
    (void)state;
    check_box_transmittance("box_inactive.vdb", 0.75,
                            "Integrator \"singlescatter\" \"string transmittance\" \"ratio\"",
                            "ratio", 1024);
    check_box_transmittance("box_inactive.vdb", 0.75,
                            "Integrator \"volpath\" \"integer maxdepth\" 1", "volpath", 1024);
    /* Marching: 8 kinks of the trilinear field along z (two at each end of
     * the box and of the slab). */
    double worst, frac;
    check_raymarch_file("box_inactive.vdb", 0.75, 8, box_axis_view, 0.25, &worst, &frac);
}

/* ---- 3. box.vdb against a homogeneous box ------------------------------------ */

/* The constant-density grid and a homogeneous medium with the same coefficients
 * filling index [-0.5, 31.5]^3 (where the grid's boundary ramps cross 1/2)
 * have the same optical depth along every line that crosses a face's ramp
 * completely, so their images agree except where a ray (or a shadow ray) runs
 * through the ramps near an edge, where the product of two ramps differs from
 * the box indicator, or grazes a face (through the grid's ramp tail beyond
 * the homogeneous box, or the homogeneous box's step beyond the grid's
 * ramp). Those pixels (EDGE below) are left out: there the images differ by
 * up to ~120 standard errors. A 32x32 image of the box lit by a distant light,
 * 512 independent samples per pixel (5-10% noise per pixel): over the ~200
 * interior pixels no pixel may differ by more than 5 standard errors of the
 * difference (measured max 3.0), and the interior mean by neither 2% nor 4.5
 * standard errors (measured -0.07..-0.4%, |z| <= 1.3). */
#define CMP_RES 32

typedef enum { RAY_MISS, RAY_INTERIOR, RAY_EDGE } ray_class;

/* Classifies the camera ray through a pixel against the box [-0.5, 31.5]^3
 * (index units, 32 per world unit; the grid's density differs from the
 * homogeneous box in the shells [-1, 0] and [31, 32] of each axis):
 *   MISS      the ray stays more than 1.5 voxels away from the box;
 *   INTERIOR  it reaches the core [1.5, 29.5]^3, so it crosses every shell
 *             it meets completely, and never has two coordinates in the
 *             grown shells [-2, 1.5] or [29.5, 33] at once (near an edge);
 *   EDGE      otherwise (grazing a face or passing an edge). */
static ray_class classify_box_ray(vec3 o, vec3 d)
{
    vec3 oi = v3_scale(o, 32.0), di = d; /* index space, same direction */
    double lo = -2.0, hi = 33.0;
    double t0 = 0.0, t1 = INFINITY;
    const double oo[3] = {oi.x, oi.y, oi.z}, dd[3] = {di.x, di.y, di.z};
    for (int a = 0; a < 3; ++a) {
        double ta = (lo - oo[a]) / dd[a], tb = (hi - oo[a]) / dd[a];
        t0 = fmax(t0, fmin(ta, tb));
        t1 = fmin(t1, fmax(ta, tb));
    }
    if (!(t0 < t1))
        return RAY_MISS;
    bool core = false;
    for (int i = 0; i <= 4000; ++i) {
        double t = t0 + (t1 - t0) * i / 4000.0;
        int in_shell = 0, in_core = 0;
        for (int a = 0; a < 3; ++a) {
            double u = oo[a] + t * dd[a];
            in_shell += u < 1.5 || u > 29.5;
            in_core += u >= 1.5 && u <= 29.5;
        }
        if (in_shell >= 2)
            return RAY_EDGE;
        core = core || in_core == 3;
    }
    return core ? RAY_INTERIOR : RAY_EDGE;
}

static char *box_compare_scene(bool grid)
{
    char *encl =
        grid ? box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1))
             : box_mesh(v3(-0.5 / 32, -0.5 / 32, -0.5 / 32), v3(31.5 / 32, 31.5 / 32, 31.5 / 32));
    char *medium = grid ? sfmt("\"nanovdb\" \"string filename\" \"%s/box.vdb\"", VOLUMES)
                        : sfmt("\"homogeneous\"");
    char *s = sfmt("LookAt 0.484375 0.484375 3.5  0.484375 0.484375 0.484375  0 1 0\n"
                   "Camera \"perspective\" \"float fov\" 34\n"
                   "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 16 \"integer seed\" 3\n"
                   "Integrator \"singlescatter\"\n"
                   "WorldBegin\n"
                   "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [1 2 3] "
                   "\"point3 to\" [0 0 0]\n"
                   "MakeNamedMedium \"m\" \"string type\" %s "
                   "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [1 2 3] \"float g\" 0.3\n"
                   "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n%s"
                   "AttributeEnd\n",
                   CMP_RES, CMP_RES, medium, encl);
    free(encl);
    free(medium);
    return s;
}

static void test_box_vdb_matches_homogeneous(void **state)
{
    (void)state;
    const int spp = 512;
    char *tg = box_compare_scene(true), *th = box_compare_scene(false);
    render_scene *rg = build(tg), *rh = build(th);
    pstat *ig = image_stats(rg, CMP_RES, CMP_RES, spp);
    pstat *ih = image_stats(rh, CMP_RES, CMP_RES, spp);
    int n[3] = {0, 0, 0};
    double sum_g[3] = {0, 0, 0}, sum_h[3] = {0, 0, 0}, var[3] = {0, 0, 0};
    double zmax = 0.0, zedge = 0.0;
    for (int i = 0; i < CMP_RES * CMP_RES; ++i) {
        vec3 o, d;
        camera_ray_world(rg, i % CMP_RES + 0.5, i / CMP_RES + 0.5, &o, &d);
        ray_class k = classify_box_ray(o, d);
        n[k]++;
        if (k == RAY_MISS) {
            /* No background light: both exactly black. */
            assert_true(rgb_is_black(ig[i].mean) && rgb_is_black(ih[i].mean));
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            double a = ch(ig[i].mean, c), b = ch(ih[i].mean, c);
            double se = hypot(ch(ig[i].se, c), ch(ih[i].se, c));
            if (k == RAY_EDGE) {
                if (se > 0.0)
                    zedge = fmax(zedge, fabs(a - b) / se);
                continue;
            }
            assert_true(a > 0.0 && b > 0.0);
            double z = (a - b) / se;
            zmax = fmax(zmax, fabs(z));
            var[c] += se * se;
            sum_g[c] += a;
            sum_h[c] += b;
            if (fabs(z) > 5.0) {
                print_error("pixel (%d, %d) channel %d: grid %.6g, homogeneous %.6g "
                            "(se %.3g, z %.2f)\n",
                            i % CMP_RES, i / CMP_RES, c, a, b, se, z);
                fail();
            }
        }
    }
    note("box.vdb vs homogeneous: %d interior, %d edge, %d miss pixels; max |z| %.2f "
         "interior, %.2f edge\n",
         n[RAY_INTERIOR], n[RAY_EDGE], n[RAY_MISS], zmax, zedge);
    assert_true(n[RAY_INTERIOR] > 150 && n[RAY_EDGE] > 50 && n[RAY_MISS] > 100);
    for (int c = 0; c < 3; ++c) {
        double rel = sum_g[c] / sum_h[c] - 1.0, z = (sum_g[c] - sum_h[c]) / sqrt(var[c]);
        note("box.vdb vs homogeneous: channel %d interior mean %.6g vs %.6g (%.3g, z %.2f)\n", c,
             sum_g[c] / n[RAY_INTERIOR], sum_h[c] / n[RAY_INTERIOR], rel, z);
        assert_true(fabs(rel) < 0.02);
        assert_true(fabs(z) < 4.5);
    }
    free(ig);
    free(ih);
    render_scene_destroy(rg);
    render_scene_destroy(rh);
    free(tg);
    free(th);
}

/* ---- 4. Airlight (Sun et al. 2005) ------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static const char *air_camera = "LookAt 0 0 0  0 0 1  0 1 0\n"
                                "MediumInterface \"\" \"fog\"\n"
                                "Camera \"perspective\" \"float fov\" 100\n"
                                "Film \"rgb\" \"integer xresolution\" 24 "
                                "\"integer yresolution\" 16\n";

/* Every pixel of a 24x16 image (fov 100 across the 16 rows) of an unbounded
 * fog lit by a point light, against the quadrature, within `tol` relative. */
/* A pixel passes within `tol` relative, or with tol 0 within 5 standard
 * errors (then the mean relative error over the image must be within 0.5%
 * and the worst relative standard error within 3x the median's: no pixel
 * is much noisier for looking past the light). */
static void check_airlight_with(const char *integrator, rgb sigma_a, rgb sigma_s, double g,
                                double I, vec3 light, int spp, double tol, const char *what)
{
    char *text = sfmt("%s"
                      "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
                      "Integrator %s\n"
                      "WorldBegin\n"
                      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" "
                      "\"rgb sigma_a\" [%.17g %.17g %.17g] \"rgb sigma_s\" [%.17g %.17g %.17g] "
                      "\"float g\" %.17g\n"
                      "LightSource \"point\" \"rgb I\" [%.17g %.17g %.17g] "
                      "\"point3 from\" [%.17g %.17g %.17g]\n",
                      air_camera, integrator, sigma_a.r, sigma_a.g, sigma_a.b, sigma_s.r,
                      sigma_s.g, sigma_s.b, g, I, I, I, light.x, light.y, light.z);
    render_scene *rs = build(text);
    pstat *px = image_stats(rs, 24, 16, spp);
    rgb sigma_t = rgb_add(sigma_a, sigma_s);
    double worst = 0.0, min_gamma = 1e9, max_gamma = 0.0, sum_rel = 0.0;
    double rse[24 * 16 * 3];
    for (int i = 0; i < 24 * 16; ++i) {
        vec3 o, d;
        camera_ray_world(rs, i % 24 + 0.5, i / 24 + 0.5, &o, &d);
        double gamma = acos(v3_dot(d, v3_normalize(v3_sub(light, o))));
        min_gamma = fmin(min_gamma, gamma);
        max_gamma = fmax(max_gamma, gamma);
        for (int c = 0; c < 3; ++c) {
            double want = airlight(ch(sigma_s, c), ch(sigma_t, c), g, I, o, d, light, INFINITY);
            double got = ch(px[i].mean, c);
            double rel = got / want - 1.0;
            worst = fmax(worst, fabs(rel));
            sum_rel += rel;
            rse[3 * i + c] = ch(px[i].se, c) / want;
            bool ok = tol > 0.0 ? fabs(rel) <= tol : fabs(got - want) <= 5.0 * ch(px[i].se, c);
            if (!ok) {
                print_error("%s pixel (%d, %d) channel %d (gamma %.2f deg): got %.7g, want "
                            "%.7g\n",
                            what, i % 24, i / 24, c, gamma * 180 / HZ_PI, got, want);
                fail();
            }
        }
    }
    qsort(rse, 24 * 16 * 3, sizeof rse[0], cmp_double);
    double mean_rel = sum_rel / (24 * 16 * 3);
    note("airlight %s (%s): worst relative error %.3g, mean %.2g, relative standard error "
         "median %.3g, worst %.3g, gamma %.2f..%.1f deg\n",
         what, integrator, worst, mean_rel, rse[24 * 16 * 3 / 2], rse[24 * 16 * 3 - 1],
         min_gamma * 180 / HZ_PI, max_gamma * 180 / HZ_PI);
    if (tol == 0.0) {
        assert_true(fabs(mean_rel) <= 0.005);
        assert_true(rse[24 * 16 * 3 - 1] <= 3.0 * rse[24 * 16 * 3 / 2]);
    }
    free(px);
    render_scene_destroy(rs);
    free(text);
}

/* The same under singlescatter, and under volpath at maxdepth 1, whose
 * equiangular light samples (volpath.c, equiangular_ld) keep the pixels
 * that look right past the light as accurate as the others. */
static void check_airlight(rgb sigma_a, rgb sigma_s, double g, double I, vec3 light, int spp,
                           double tol, const char *what)
{
    check_airlight_with("\"singlescatter\"", sigma_a, sigma_s, g, I, light, spp, tol, what);
    check_airlight_with("\"volpath\" \"integer maxdepth\" 1", sigma_a, sigma_s, g, I, light,
                        2 * spp, 0.0, what);
}

static void test_airlight(void **state)
{
    (void)state;
    /* The light 2.5 away, 0.15 pixel beside the ray of pixel (13, 9) (0.9°),
     * so that pixel and its neighbours look right past it. */
    char *cam_only =
        sfmt("%sWorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n", air_camera);
    render_scene *rs = build(cam_only);
    vec3 o, d;
    camera_ray_world(rs, 13.5 + 0.12, 9.5 + 0.09, &o, &d);
    render_scene_destroy(rs);
    free(cam_only);
    vec3 light = v3_add(o, v3_scale(d, 2.5));
    /* σ_t·D = 0.75, 1.1, 0.38 */
    check_airlight(rgb_make(0.1, 0.15, 0.05), rgb_make(0.2, 0.3, 0.1), 0.0, 5.0, light, 512, 0.01,
                   "thick");
    /* σ_t·D = 0.05 .. 0.1 */
    check_airlight(rgb_make(0.01, 0.01, 0.005), rgb_make(0.01, 0.03, 0.015), 0.0, 5.0, light, 512,
                   0.01, "thin");
    /* Anisotropic: the phase function at the scattering angle sin θ. The light
     * sampling strategies ignore the phase, so these need more samples. */
    check_airlight(rgb_make(0.1, 0.15, 0.05), rgb_make(0.2, 0.3, 0.1), 0.6, 5.0, light, 1024, 0.01,
                   "g=0.6");
    check_airlight(rgb_make(0.1, 0.15, 0.05), rgb_make(0.2, 0.3, 0.1), -0.4, 5.0, light, 1024, 0.01,
                   "g=-0.4");
}

/* ---- 5. No light leaks --------------------------------------------------------- */

#define ROOM_RES 16

static const char *room_camera = "LookAt 0.5 0.2 -1  0.3 0 1  0 1 0\n"
                                 "MediumInterface \"\" \"fog\"\n"
                                 "Camera \"perspective\" \"float fov\" 70\n"
                                 "Film \"rgb\" \"integer xresolution\" 16 "
                                 "\"integer yresolution\" 16\n"
                                 "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
                                 "Integrator \"singlescatter\"\n";

/* Every kind of light, all outside the radius-3.2 ball around the origin. */
static const char *outside_lights =
    "LightSource \"point\" \"rgb I\" [50 50 50] \"point3 from\" [0 0 5]\n"
    "LightSource \"spot\" \"rgb I\" [50 50 50] \"point3 from\" [4.5 0 0] \"point3 to\" [0 0 0] "
    "\"float coneangle\" 40\n"
    "LightSource \"distant\" \"rgb L\" [5 5 5] \"point3 from\" [1 2 3] \"point3 to\" [0 0 0]\n"
    "LightSource \"infinite\" \"rgb L\" [2 2 2]\n"
    "AttributeBegin\nTranslate 0 -5 0\nAreaLightSource \"diffuse\" \"rgb L\" [20 20 20]\n"
    "Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n";

static const char *room_fog = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" "
                              "\"rgb sigma_a\" [0.05 0.05 0.05] \"rgb sigma_s\" [0.3 0.2 0.1]\n";

/* Renders ROOM_RES² pixels; returns how many have a non-zero sample (every
 * sample is finite and >= 0, or the test fails). */
static int lit_pixels(const char *text, int spp)
{
    render_scene *rs = build(text);
    pstat *px = image_stats(rs, ROOM_RES, ROOM_RES, spp);
    int lit = 0;
    for (int i = 0; i < ROOM_RES * ROOM_RES; ++i) {
        assert_true(px[i].min >= 0.0);
        lit += !rgb_is_black(px[i].mean);
    }
    free(px);
    render_scene_destroy(rs);
    return lit;
}

static void test_no_light_leaks(void **state)
{
    (void)state;
    /* A closed opaque room (a sphere, then a six-sided box mesh) filled with
     * fog, the camera inside: with every light outside, the image is exactly
     * black; with the same lights and no walls it is lit everywhere. */
    char *box = box_mesh(v3(-3, -3, -3), v3(3, 3, 3));
    const char *walls[2] = {"Shape \"sphere\" \"float radius\" 3\n", box};
    for (int w = 0; w < 2; ++w) {
        char *text = sfmt("%sWorldBegin\n%s%s"
                          "AttributeBegin\nMediumInterface \"fog\" \"\"\n"
                          "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n%s"
                          "AttributeEnd\n",
                          room_camera, room_fog, outside_lights, walls[w]);
        int lit = lit_pixels(text, 64);
        note("closed room %d, lights outside: %d lit pixels\n", w, lit);
        assert_int_equal(lit, 0);
        free(text);
    }
    char *open_room = sfmt("%sWorldBegin\n%s%s", room_camera, room_fog, outside_lights);
    assert_int_equal(lit_pixels(open_room, 4), ROOM_RES * ROOM_RES);
    free(open_room);

    /* The light inside the room: walls and fog are lit. */
    char *inside = sfmt("%sWorldBegin\n%s"
                        "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0 1 0.5]\n"
                        "AttributeBegin\nMediumInterface \"fog\" \"\"\n"
                        "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n%s"
                        "AttributeEnd\n",
                        room_camera, room_fog, box);
    assert_int_equal(lit_pixels(inside, 4), ROOM_RES * ROOM_RES);
    free(inside);
    free(box);
}

/* The sphere room of radius 3 with a point light inside: the wall seen along a
 * camera ray of length ℓ (camera in the fog) shows
 *   e^{-σ_t ℓ} ρ/π I cos θ_w e^{-σ_t r} / r²   (r: wall to light)
 * plus the airlight of [0, ℓ]. */
static void check_lit_room(rgb sigma_a, rgb sigma_s, rgb rho, int spp, double tol, const char *what)
{
    vec3 light = v3(0.4, 1.0, 0.5);
    const double I = 5.0, R = 3.0;
    char *text = sfmt("%sWorldBegin\n"
                      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" "
                      "\"rgb sigma_a\" [%g %g %g] \"rgb sigma_s\" [%g %g %g]\n"
                      "LightSource \"point\" \"rgb I\" [%g %g %g] \"point3 from\" [%g %g %g]\n"
                      "AttributeBegin\nMediumInterface \"fog\" \"\"\n"
                      "Material \"diffuse\" \"rgb reflectance\" [%g %g %g]\n"
                      "Shape \"sphere\" \"float radius\" %g\nAttributeEnd\n",
                      room_camera, sigma_a.r, sigma_a.g, sigma_a.b, sigma_s.r, sigma_s.g, sigma_s.b,
                      I, I, I, light.x, light.y, light.z, rho.r, rho.g, rho.b, R);
    render_scene *rs = build(text);
    pstat *px = image_stats(rs, ROOM_RES, ROOM_RES, spp);
    rgb sigma_t = rgb_add(sigma_a, sigma_s);
    double worst = 0.0;
    for (int i = 0; i < ROOM_RES * ROOM_RES; ++i) {
        vec3 o, d;
        camera_ray_world(rs, i % ROOM_RES + 0.5, i / ROOM_RES + 0.5, &o, &d);
        bool grazing;
        double ell = sphere_path(o, d, R, &grazing); /* o is inside: the distance to the wall */
        vec3 p = v3_add(o, v3_scale(d, ell));
        vec3 to_light = v3_sub(light, p);
        double r = v3_length(to_light);
        double cos_w = v3_dot(v3_scale(p, -1.0 / R), to_light) / r;
        for (int c = 0; c < 3; ++c) {
            double st = ch(sigma_t, c);
            double want =
                exp(-st * ell) * ch(rho, c) * HZ_INV_PI * I * cos_w * exp(-st * r) / (r * r);
            if (ch(sigma_s, c) > 0.0)
                want += airlight(ch(sigma_s, c), st, 0.0, I, o, d, light, ell);
            double got = ch(px[i].mean, c);
            double allow = tol;
            if (spp == 1) /* the deterministic case: the shadow ray's known shortfall */
                allow += st * r * GEOMETRY_SHADOW_EPSILON;
            worst = fmax(worst, fabs(got / want - 1.0));
            if (!(fabs(got / want - 1.0) <= allow)) {
                print_error("%s pixel %d channel %d: got %.7g, want %.7g\n", what, i, c, got, want);
                fail();
            }
        }
    }
    note("lit room %s: worst relative error %.3g\n", what, worst);
    free(px);
    render_scene_destroy(rs);
    free(text);
}

static void test_lit_room(void **state)
{
    (void)state;
    /* Absorbing fog: deterministic and exact but for the shadow ray, which
     * stops GEOMETRY_SHADOW_EPSILON·r short of the light (pbrt-v4's
     * ShadowEpsilon) and so misses that much attenuation (measured 1.2e-4 of
     * which 1.0e-4 is that), and starts at a point lifted off the wall. */
    check_lit_room(rgb_make(0.2, 0.3, 0.4), rgb_grey(0.0), rgb_make(0.2, 0.5, 0.8), 1, 3e-5,
                   "absorbing");
    /* Scattering fog with black walls: the airlight of the segment alone. */
    check_lit_room(rgb_make(0.05, 0.05, 0.05), rgb_make(0.3, 0.2, 0.1), rgb_grey(0.0), 512, 0.01,
                   "black walls");
    /* Both. */
    check_lit_room(rgb_make(0.05, 0.05, 0.05), rgb_make(0.3, 0.2, 0.1), rgb_make(0.2, 0.5, 0.8),
                   512, 0.01, "grey walls");
}

static void test_wall_shadows_fog(void **state)
{
    (void)state;
    /* Unbounded fog above and below an opaque floor z = 0 (80x80); the light
     * is under it, the camera above looks along it: every fog point the camera
     * sees and the floor's top are in shadow, so the image is exactly black.
     * Without the floor it is lit everywhere. */
    const char *head = "LookAt 0 0 1  1 0 1  0 0 1\n"
                       "MediumInterface \"\" \"fog\"\n"
                       "Camera \"perspective\" \"float fov\" 60\n"
                       "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                       "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
                       "Integrator \"singlescatter\"\n"
                       "WorldBegin\n"
                       "LightSource \"point\" \"rgb I\" [50 50 50] \"point3 from\" [3 0 -1]\n";
    const char *floor_quad =
        "AttributeBegin\nMediumInterface \"fog\" \"fog\"\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
        "Shape \"trianglemesh\" \"point3 P\" [-40 -40 0  40 -40 0  40 40 0  -40 40 0]\n"
        "  \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n";
    char *with = sfmt("%s%s%s", head, room_fog, floor_quad);
    char *without = sfmt("%s%s", head, room_fog);
    assert_int_equal(lit_pixels(with, 64), 0);
    assert_int_equal(lit_pixels(without, 4), ROOM_RES * ROOM_RES);
    free(with);
    free(without);
}

/* ---- 6. Estimator agreement on smoke.vdb -------------------------------------- */

#define SMOKE_W 16
#define SMOKE_H 32

static char *smoke_scene_scaled(const char *integrator, double scale)
{
    char *encl = box_mesh(v3(-0.5, -0.1, -0.5), v3(0.4, 2.1, 0.45));
    char *s = sfmt("LookAt 0 1 4  -0.05 1 0  0 1 0\n"
                   "Camera \"perspective\" \"float fov\" 14\n"
                   "Film \"rgb\" \"integer xresolution\" %d \"integer yresolution\" %d\n"
                   "Sampler \"independent\" \"integer pixelsamples\" 16 \"integer seed\" 11\n"
                   "%s\n"
                   "WorldBegin\n"
                   "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [1 1.5 1] "
                   "\"point3 to\" [0 0 0]\n"
                   "MakeNamedMedium \"smoke\" \"string type\" \"nanovdb\" "
                   "\"string filename\" \"%s/smoke.vdb\" "
                   "\"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [4 6 8] \"float scale\" %g\n"
                   "AttributeBegin\nMediumInterface \"smoke\" \"\"\nMaterial \"interface\"\n%s"
                   "AttributeEnd\n",
                   SMOKE_W, SMOKE_H, integrator, VOLUMES, scale, encl);
    free(encl);
    return s;
}

static char *smoke_scene(const char *integrator) { return smoke_scene_scaled(integrator, 2.0); }

/* raymarch at pixel centres is deterministic, in thick media too (its march
 * ends at a transmittance cut-off, not by roulette): two seeds give the same
 * image, and two seeds of jittered marching do not. In RGB: the coloured
 * smoke would render spectrally by default, where the wavelengths are the
 * seed's. */
static void test_raymarch_seed_independent(void **state)
{
    (void)state;
    char out[4096], path[512], args[2048];
    const char *modes[2] = {"raymarch", "jittered"};
    for (int m = 0; m < 2; ++m) {
        char integ[256];
        snprintf(integ, sizeof integ,
                 "Integrator \"singlescatter\" \"string transmittance\" \"%s\" "
                 "\"float stepsize\" 0.5",
                 modes[m]);
        char *text = smoke_scene_scaled(integ, 40.0);
        /* The Sampler's seed (which wins over --seed): 11, then 12. */
        char *seed_at = strstr(text, "\"integer seed\" 11");
        assert_non_null(seed_at);
        for (int seed = 0; seed < 2; ++seed) {
            seed_at[strlen("\"integer seed\" 1")] = (char)('1' + seed);
            snprintf(path, sizeof path, "%s/seed_%s.pbrt", HAZE_TMP, modes[m]);
            write_text_file(path, text);
            snprintf(args, sizeof args,
                     "render '%s' -o '%s/seed_%s_%d.exr' --quiet --spp 1 "
                     "--disable-pixel-jitter --color rgb",
                     path, HAZE_TMP, modes[m], seed);
            assert_int_equal(run_haze(args, out, sizeof out), 0);
        }
        free(text);
        char a[600], b[600];
        snprintf(a, sizeof a, "%s/seed_%s_0.exr", HAZE_TMP, modes[m]);
        snprintf(b, sizeof b, "%s/seed_%s_1.exr", HAZE_TMP, modes[m]);
        assert_true(exr_pixels_equal(a, b) == (m == 0));
    }
}

/* Mean radiance over the image and its standard error. */
static void smoke_mean(const char *integrator, int spp, rgb *mean, rgb *se)
{
    char *text = smoke_scene(integrator);
    render_scene *rs = build(text);
    pstat *px = image_stats(rs, SMOKE_W, SMOKE_H, spp);
    double m[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    const int n = SMOKE_W * SMOKE_H;
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            m[c] += ch(px[i].mean, c) / n;
            v[c] += ch(px[i].se, c) * ch(px[i].se, c) / ((double)n * n);
        }
    *mean = rgb_make(m[0], m[1], m[2]);
    *se = rgb_make(sqrt(v[0]), sqrt(v[1]), sqrt(v[2]));
    free(px);
    render_scene_destroy(rs);
    free(text);
}

/* The plume of volumes/smoke.vdb (σ_t up to 2·9·0.9 per unit, optical depths
 * of a few across), lit by a distant light, 16x32 pixels: the image means of
 * fixed-step marching (stepsize 0.5, shadow rays at the default 2 and at 0.5
 * voxels) and of jittered marching (0.5) against unbiased ratio tracking at
 * 256 samples per pixel (standard error ~0.2%). Measured: raymarch 0.5/2
 * +0.4..0.7%, jittered +0.3..0.6%, raymarch 0.5/0.5 +0.15..0.25% (the three
 * channels); the tolerance is 1.5%. */
static void test_estimators_agree(void **state)
{
    (void)state;
    enum { N = 5 };
    const char *names[N] = {"ratio", "raymarch 0.5", "jittered 0.5", "raymarch 0.5/0.5",
                            "residual"};
    const char *args[N] = {
        "\"ratio\"",
        "\"raymarch\" \"float stepsize\" 0.5",
        "\"jittered\" \"float stepsize\" 0.5",
        "\"raymarch\" \"float stepsize\" 0.5 \"float shadowstepsize\" 0.5",
        "\"residual\"",
    };
    const int spp[N] = {256, 64, 64, 64, 128};
    rgb mean[N], se[N];
    for (int k = 0; k < N; ++k) {
        char *integ = sfmt("Integrator \"singlescatter\" \"string transmittance\" %s", args[k]);
        smoke_mean(integ, spp[k], &mean[k], &se[k]);
        free(integ);
        note("smoke %-16s mean %.6g %.6g %.6g  (se %.2g %.2g %.2g)\n", names[k], mean[k].r,
             mean[k].g, mean[k].b, se[k].r, se[k].g, se[k].b);
    }
    for (int c = 0; c < 3; ++c)
        assert_true(ch(se[0], c) < 0.004 * ch(mean[0], c)); /* the reference is precise */
    for (int k = 1; k < N; ++k)
        for (int c = 0; c < 3; ++c) {
            double rel = ch(mean[k], c) / ch(mean[0], c) - 1.0;
            note("smoke %s vs ratio channel %d: %.4g (%.2f se)\n", names[k], c, rel,
                 (ch(mean[k], c) - ch(mean[0], c)) / hypot(ch(se[k], c), ch(se[0], c)));
            assert_true(fabs(rel) < 0.015);
        }
}

/* ---- 7. Sanity at extreme parameters -------------------------------------------- */

/* The sphere of radius 1.2 filled with `medium` ("ink"), lit by a distant
 * light from the camera's side, in front of the emitting quad of ink_scene if
 * `emitter` (which also lights the sphere's sides from behind). */
static char *dense_scene(const char *sampler, const char *medium, bool emitter)
{
    return sfmt("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                "%s\nIntegrator \"singlescatter\"\n"
                "WorldBegin\n"
                "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" %s\n"
                "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [0 0 1] "
                "\"point3 to\" [0 0 0]\n"
                "%s"
                "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n"
                "Shape \"sphere\" \"float radius\" 1.2\nAttributeEnd\n",
                sampler, medium,
                emitter ? "AttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                          "AreaLightSource \"diffuse\" \"rgb L\" [2 3 4] \"bool twosided\" true\n"
                          "Shape \"trianglemesh\" \"point3 P\" [-20 -20 -3  20 -20 -3  20 20 -3  "
                          "-20 20 -3]\n  \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n"
                        : "");
}

static void test_extreme_density(void **state)
{
    (void)state;
    /* Opaque: an absorbing sphere of σ_t = 1e12 hides the emitter behind it
     * exactly; everything else sees it unattenuated (the distant light has
     * nothing to light: no scattering, a black emitter surface). */
    char *text = dense_scene("Sampler \"independent\" \"integer pixelsamples\" 1",
                             "\"rgb sigma_a\" [1 2 3] \"rgb sigma_s\" [0 0 0] "
                             "\"float scale\" 1e12",
                             true);
    render_scene *rs = build(text);
    int hidden = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            vec3 o, d;
            camera_ray_world(rs, x + 0.5, y + 0.5, &o, &d);
            bool grazing;
            double len = sphere_path(o, d, 1.2, &grazing);
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            if (grazing)
                continue;
            if (len > 0.0) {
                assert_true(rgb_is_black(e.L));
                ++hidden;
            } else {
                expect_rgb_close(e.L, emit_L, 1e-12, 0, "beside the opaque sphere", x, y);
            }
        }
    assert_true(hidden > 150);
    render_scene_destroy(rs);
    free(text);

    /* A dense scattering sphere lit from the camera's side: single scattering
     * from a half-space of albedo ω seen at μ = cos(view, normal) and lit at
     * μ0 = cos(light, normal) gives
     *   L = ω p E μ0 / (μ0 + μ)
     * (∫ σ_s p E e^{-σ_t s (1 + μ/μ0)} ds). With scale 1000 the mean free path
     * (1e-3) is far below the radius, so the sphere is locally that
     * half-space. Measured: within 0.6% at 512 zsobol samples per pixel (0.14%
     * at 4096: no bias). (Denser, haze darkens: at scale 1e6 the centre is
     * 9% dark, at 1e9 black. Scattering points within float rounding (~2e-7
     * here) of the boundary start shadow rays whose float origin lies outside
     * the sphere; they find no exit and count as never leaving the medium.) */
    text = dense_scene("Sampler \"zsobol\" \"integer pixelsamples\" 16",
                       "\"rgb sigma_a\" [0 0.5 1] \"rgb sigma_s\" [1 1 1] "
                       "\"float scale\" 1000",
                       false);
    rs = build(text);
    pstat *px = image_stats(rs, 16, 16, 512);
    const rgb albedo = {1.0, 1.0 / 1.5, 0.5, 1.0 / 1.5};
    double worst = 0.0;
    int checked = 0;
    for (int i = 0; i < 256; ++i) {
        vec3 o, d;
        camera_ray_world(rs, i % 16 + 0.5, i / 16 + 0.5, &o, &d);
        bool grazing;
        if (sphere_path(o, d, 1.2, &grazing) <= 0.0)
            continue;
        double b = v3_dot(o, d);
        double t = -b - sqrt(b * b - (v3_length_sq(o) - 1.44));
        vec3 n = v3_scale(v3_add(o, v3_scale(d, t)), 1.0 / 1.2);
        double mu = -v3_dot(n, d), mu0 = n.z;
        if (mu < 0.5 || mu0 < 0.5)
            continue; /* near the rim: curvature matters on the scale of a free path */
        for (int c = 0; c < 3; ++c) {
            double want = ch(albedo, c) / (4.0 * HZ_PI) * 3.0 * mu0 / (mu0 + mu);
            double rel = ch(px[i].mean, c) / want - 1.0;
            worst = fmax(worst, fabs(rel));
            if (!(fabs(rel) < 0.02)) {
                print_error("dense sphere pixel %d channel %d: got %.6g, want %.6g\n", i, c,
                            ch(px[i].mean, c), want);
                fail();
            }
        }
        ++checked;
    }
    note("dense scattering sphere (scale 1000): worst relative error %.3g over %d pixels\n", worst,
         checked);
    assert_true(checked > 100);
    free(px);
    render_scene_destroy(rs);
    free(text);

    /* Scattering at scale 1e12: finite and non-negative everywhere
     * (image_stats fails on a non-finite sample), the emitter hidden. */
    text = dense_scene("Sampler \"zsobol\" \"integer pixelsamples\" 16",
                       "\"rgb sigma_a\" [0 0.5 1] \"rgb sigma_s\" [1 1 1] "
                       "\"float scale\" 1e12 \"float g\" 0.5",
                       true);
    rs = build(text);
    px = image_stats(rs, 16, 16, 16);
    for (int i = 0; i < 256; ++i) {
        assert_true(px[i].min >= 0.0);
        assert_true(rgb_max(px[i].mean) <= 4.0);
    }
    free(px);
    render_scene_destroy(rs);
    free(text);
}

/* box.vdb at density scale 1e12 in front of a sky: behind it black, every
 * pixel finite, with each estimator. */
static void test_extreme_density_grid(void **state)
{
    (void)state;
    for (int mode = 0; mode < 3; ++mode) {
        const char *m = mode == 0 ? "ratio" : mode == 1 ? "raymarch" : "jittered";
        char integ[128];
        snprintf(integ, sizeof integ,
                 "Integrator \"singlescatter\" \"string transmittance\" \"%s\"", m);
        char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
        char *text = sfmt("%s"
                          "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                          "Sampler \"independent\" \"integer pixelsamples\" 1\n%s\n"
                          "WorldBegin\n"
                          "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                          "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [1 2 3] "
                          "\"point3 to\" [0 0 0]\n"
                          "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                          "\"string filename\" \"%s/box.vdb\" \"rgb sigma_a\" [0.5 1 2] "
                          "\"rgb sigma_s\" [1 1 1] \"float scale\" 1e12 \"float g\" -0.3\n"
                          "AttributeBegin\nMediumInterface \"box\" \"\"\nMaterial \"interface\"\n"
                          "%sAttributeEnd\n",
                          box_axis_view, integ, VOLUMES, encl);
        render_scene *rs = build(text);
        /* Ratio tracking against a majorant of 3e12 crosses the boundary ramp
         * in ~1e6 tentative collisions before Russian roulette ends the walk
         * (~0.2 s per camera ray), so it gets 4 pixels. */
        int npx = mode == 0 ? 4 : 64;
        for (int i = 0; i < npx; ++i) {
            int x = mode == 0 ? 2 + 3 * (i % 2) : i % 8, y = mode == 0 ? 2 + 3 * (i / 2) : i / 8;
            pstat p = pixel_stats_raw(rs, x, y, 1);
            assert_true(p.finite);
            assert_true(rgb_is_black(p.mean));
        }
        render_scene_destroy(rs);
        free(text);
        free(encl);
    }
}

/* Density scale 1e-12: the image equals the one without any medium within
 * 1e-6 (a diffuse floor, a point light; the media between them and the
 * camera). */
static void test_vanishing_density(void **state)
{
    (void)state;
    const char *camera = "LookAt 0 0 5  0 0 0  0 1 0\n"
                         "Camera \"perspective\" \"float fov\" 60\n"
                         "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                         "Sampler \"independent\" \"integer pixelsamples\" 1\n"
                         "Integrator \"singlescatter\"\n";
    const char *world = "WorldBegin\n"
                        "LightSource \"point\" \"rgb I\" [4 4 4] \"point3 from\" [0.3 -0.2 2]\n"
                        "Material \"diffuse\" \"rgb reflectance\" [0.2 0.5 0.8]\n"
                        "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  "
                        "-20 20 0]\n  \"integer indices\" [0 1 2 0 2 3]\n";
    char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
    /* A homogeneous sphere over the light and the floor, box.vdb beside it,
     * and the camera in an unbounded thin fog. */
    char *media = sfmt(
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 2 3] "
        "\"rgb sigma_s\" [3 2 1] \"float scale\" 1e-12\n"
        "MakeNamedMedium \"ball\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 2 3] "
        "\"rgb sigma_s\" [3 2 1] \"float scale\" 1e-12 \"float g\" 0.7\n"
        "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" \"string filename\" "
        "\"%s/box.vdb\" \"rgb sigma_a\" [1 2 3] \"rgb sigma_s\" [3 2 1] \"float scale\" 1e-12\n"
        "AttributeBegin\nMediumInterface \"ball\" \"fog\"\nMaterial \"interface\"\n"
        "Translate 0 0 1\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n"
        "AttributeBegin\nMediumInterface \"box\" \"fog\"\nMaterial \"interface\"\n"
        "Translate -1.8 -0.5 0.2\n%sAttributeEnd\n",
        VOLUMES, encl);
    char *plain = sfmt("%s%s", camera, world);
    char *foggy = sfmt("MediumInterface \"\" \"fog\"\n%s%s"
                       "MediumInterface \"fog\" \"fog\"\n%s",
                       camera, world, media);
    render_scene *ra = build(plain), *rb = build(foggy);
    double worst = 0.0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            pixel_eval a = eval_pixel(ra, x + 0.5, y + 0.5, 1);
            pixel_eval b = eval_pixel(rb, x + 0.5, y + 0.5, 4);
            assert_true(a.L.r > 0.0);
            for (int c = 0; c < 3; ++c)
                worst = fmax(worst, fabs(ch(b.L, c) / ch(a.L, c) - 1.0));
            expect_rgb_close(b.L, a.L, 1e-6, 0, "scale 1e-12 against no medium", x, y);
        }
    note("density scale 1e-12: worst relative difference %.3g\n", worst);
    render_scene_destroy(ra);
    render_scene_destroy(rb);
    free(plain);
    free(foggy);
    free(media);
    free(encl);
}

/* g = ±0.99999: every sample finite and non-negative, the image lit. */
static void test_extreme_g(void **state)
{
    (void)state;
    const double gs[2] = {0.99999, -0.99999};
    for (int k = 0; k < 2; ++k) {
        char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
        char *text = sfmt(
            "LookAt 0.5 0.5 -2  0.5 0.5 1  0 1 0\n"
            "MediumInterface \"\" \"fog\"\n"
            "Camera \"perspective\" \"float fov\" 70\n"
            "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
            "Sampler \"zsobol\" \"integer pixelsamples\" 16\n"
            "Integrator \"singlescatter\"\n"
            "WorldBegin\n"
            "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.05 0.05 "
            "0.05] \"rgb sigma_s\" [0.2 0.3 0.4] \"float g\" %.17g\n"
            "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" \"string filename\" "
            "\"%s/box.vdb\" \"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [2 2 2] "
            "\"float g\" %.17g\n"
            "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0.6 0.4 3]\n"
            "LightSource \"spot\" \"rgb I\" [5 5 5] \"point3 from\" [0.5 0.5 -1] "
            "\"point3 to\" [0.5 0.5 3] \"float coneangle\" 20\n"
            "LightSource \"distant\" \"rgb L\" [1 1 1] \"point3 from\" [0 0 -1] "
            "\"point3 to\" [0 0 0]\n"
            "LightSource \"infinite\" \"rgb L\" [0.2 0.2 0.2]\n"
            "AttributeBegin\nMediumInterface \"box\" \"fog\"\nMaterial \"interface\"\n%s"
            "AttributeEnd\n",
            gs[k], VOLUMES, gs[k], encl);
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 16, 16, 16);
        int lit = 0;
        for (int i = 0; i < 256; ++i) {
            assert_true(px[i].min >= 0.0);
            lit += rgb_max(px[i].mean) > 0.0;
        }
        assert_int_equal(lit, 256);
        free(px);
        render_scene_destroy(rs);
        free(text);
        free(encl);
    }
}

/* sparse.vdb's balls in an interface box over a floor, under a low distant
 * light that casts their shadows on the floor beside the box (+x), seen from
 * above that floor; with `blocker`, a box of zero-density homogeneous medium
 * below the floor, out of every ray's way. */
static char *sparse_floor_scene(const char *integrator, bool blocker)
{
    char *encl = box_mesh(v3(-1.05, -0.05, -1.05), v3(1.05, 2.05, 1.05));
    char *far = box_mesh(v3(-1, -31, -1), v3(1, -29, 1));
    char *s = sfmt("LookAt 6 4 0   2.5 -0.1 0   0 1 0\n"
                   "Camera \"perspective\" \"float fov\" 50\n"
                   "Film \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 36\n"
                   "%s\n"
                   "WorldBegin\n"
                   "LightSource \"distant\" \"point3 from\" [-3 1.5 0] \"point3 to\" [0 0 0]\n"
                   "    \"rgb L\" [6 6 5.7]\n"
                   "MakeNamedMedium \"blobs\" \"string type\" \"nanovdb\"\n"
                   "    \"string filename\" \"%s/sparse.vdb\" \"string gridname\" \"density\"\n"
                   "    \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [20 20 20] \"float g\" 0.3\n"
                   "Material \"diffuse\" \"rgb reflectance\" [0.3 0.3 0.3]\n"
                   "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
                   "    \"point3 P\" [-20 -0.1 -20  20 -0.1 -20  20 -0.1 20  -20 -0.1 20]\n"
                   "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"blobs\" \"\"\n%s"
                   "AttributeEnd\n"
                   "%s%s%s",
                   integrator, VOLUMES, encl,
                   blocker ? "MakeNamedMedium \"clear\" \"string type\" \"homogeneous\"\n"
                             "    \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0 0 0]\n"
                             "AttributeBegin\nMaterial \"interface\"\nMediumInterface \"clear\" \"\"\n"
                           : "",
                   blocker ? far : "", blocker ? "AttributeEnd\n" : "");
    free(encl);
    free(far);
    return s;
}

/* A shadow ray from vacuum whose media hold no density along it is an
 * occlusion test (media_clear_along); where it meets a ball it is a walk.
 * With the homogeneous medium in the scene the test never applies (every ray
 * walks): the two images agree pixel for pixel, balls' shadows on the floor
 * included, and both have them; under singlescatter (raymarch) and volpath
 * (one bounce: direct light). */
static void check_clear_shadow_rays(const char *integrator)
{
    char *ta = sparse_floor_scene(integrator, false), *tb = sparse_floor_scene(integrator, true);
    render_scene *a = build(ta), *b = build(tb);
    free(ta);
    free(tb);
    int differ = 0;
    double lo = INFINITY, hi = 0.0;
    for (int y = 0; y < 36; ++y)
        for (int x = 0; x < 48; ++x) {
            pixel_eval pa = eval_pixel(a, x + 0.5, y + 0.5, 1);
            pixel_eval pb = eval_pixel(b, x + 0.5, y + 0.5, 1);
            if (pa.L.r != pb.L.r || pa.L.g != pb.L.g || pa.L.b != pb.L.b) {
                if (differ++ < 5)
                    print_error("pixel (%d, %d): %.17g %.17g %.17g against %.17g %.17g %.17g\n", x,
                                y, pa.L.r, pa.L.g, pa.L.b, pb.L.r, pb.L.g, pb.L.b);
            }
            if (pa.hit && pa.p_world.y < -0.09 && pa.p_world.x > 1.2 && pa.p_world.x < 5) {
                lo = fmin(lo, pa.L.r); /* the floor beside the box: lit, and shadowed */
                hi = fmax(hi, pa.L.r);
            }
        }
    assert_int_equal(differ, 0);
    print_message("floor beside the box: %g .. %g\n", lo, hi);
    assert_true(hi > 0.1);
    assert_true(lo < 0.5 * hi); /* a ball's shadow */
    render_scene_destroy(a);
    render_scene_destroy(b);
}

static void test_clear_shadow_rays(void **state)
{
    (void)state;
    check_clear_shadow_rays("Integrator \"singlescatter\" \"string transmittance\" \"raymarch\"");
    check_clear_shadow_rays("Integrator \"volpath\" \"integer maxdepth\" 1");
}

/* Shadow rays of one pixel's 16 samples of box.vdb lit by a point light,
 * marched camera rays, ratio-tracked shadow rays, `n` light samples. */
static uint64_t box_shadow_rays(int n)
{
    char *integrator = sfmt("Integrator \"singlescatter\" \"string transmittance\" \"raymarch\" "
                            "\"string shadowtransmittance\" \"ratio\" \"integer lightsamples\" %d",
                            n);
    char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
    char *text = sfmt("%s"
                      "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                      "Sampler \"independent\" \"integer pixelsamples\" 16\n%s\n"
                      "WorldBegin\n"
                      "LightSource \"point\" \"point3 from\" [0.5 2 0.5] \"rgb I\" [1 1 1]\n"
                      "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                      "\"string filename\" \"%s/box.vdb\" "
                      "\"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [1 1 1]\n"
                      "AttributeBegin\nMediumInterface \"box\" \"\"\nMaterial \"interface\"\n%s"
                      "AttributeEnd\n",
                      box_axis_view, integrator, VOLUMES, encl);
    render_scene *rs = build(text);
    const camera *cam = render_scene_camera(rs);
    camera_sample cs = {v2(4.5, 4.5), v2(0.5, 0.5), 0.5, 1.0};
    ray_differential rd;
    assert_true(camera_generate_ray_differential(cam, cs, &rd));
    integrator_counters counters = {0};
    for (int i = 0; i < 16; ++i) {
        sampler_state st;
        sampler_start(render_scene_sampler(rs), 4, 4, i, &st);
        double depth;
        (void)render_scene_li(rs, &rd, &st, &depth, &counters);
    }
    render_scene_destroy(rs);
    free(text);
    free(encl);
    free(integrator);
    return counters.shadow_rays;
}

/* "lightsamples" counts under marched camera rays with tracked shadow rays:
 * the shadows are stochastic, so each in-scattering sample takes that many
 * shadow rays of a point light too (issue 42: the test read the camera
 * rays' estimator, and a point light got one shadow ray at any count). */
static void test_lightsamples_with_tracked_shadows(void **state)
{
    (void)state;
    uint64_t one = box_shadow_rays(1), four = box_shadow_rays(4);
    print_message("shadow rays: %llu at 1 light sample, %llu at 4\n", (unsigned long long)one,
                  (unsigned long long)four);
    assert_true(one > 0);
    assert_int_equal(four, 4 * one);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lightsamples_with_tracked_shadows),
        cmocka_unit_test(test_beer_lambert_homogeneous),
        cmocka_unit_test(test_beer_lambert_box_vdb_ratio),
        cmocka_unit_test(test_beer_lambert_box_vdb_raymarch),
        cmocka_unit_test(test_inactive_voxels_are_background),
        cmocka_unit_test(test_box_vdb_matches_homogeneous),
        cmocka_unit_test(test_airlight),
        cmocka_unit_test(test_no_light_leaks),
        cmocka_unit_test(test_lit_room),
        cmocka_unit_test(test_wall_shadows_fog),
        cmocka_unit_test(test_estimators_agree),
        cmocka_unit_test(test_raymarch_seed_independent),
        cmocka_unit_test(test_extreme_density),
        cmocka_unit_test(test_extreme_density_grid),
        cmocka_unit_test(test_vanishing_density),
        cmocka_unit_test(test_extreme_g),
        cmocka_unit_test(test_clear_shadow_rays),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
