/* The extremes suite, media half (the camera and film half is test_extremes.c):
 * media at the limits of their parameters, each with an assertion on the
 * result. Every sample must be finite (image_stats fails on one that is not).
 * Cases already covered by test_media.c are not repeated here: density scale
 * 1e-12 against no medium (test_vanishing_density), the opaque absorbing
 * sphere at 1e12 (test_extreme_density) and box.vdb at 1e12 behind black with
 * every estimator (test_extreme_density_grid). Set HAZE_MEDIA_VERBOSE=1 to
 * print the measured figures. */
#define _POSIX_C_SOURCE 200809L
#include <time.h>

#include "render/media_test_util.h"

#include "render/renderer.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Mean and standard error of the mean over all pixels of an image's stats. */
static void image_mean(const pstat *px, int n, rgb *mean, rgb *se)
{
    double m[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            m[c] += ch(px[i].mean, c) / n;
            v[c] += ch(px[i].se, c) * ch(px[i].se, c) / ((double)n * n);
        }
    *mean = rgb_make(m[0], m[1], m[2]);
    *se = rgb_make(sqrt(v[0]), sqrt(v[1]), sqrt(v[2]));
}

/* ---- a dense slab: single scattering from a semi-infinite medium ---------- */

/* The slab [-10, 10]² x [-1, 0] of homogeneous "ink" (albedo 1, 2/3, 1/2),
 * seen straight down (μ = 1) by an orthographic camera, lit by a distant light
 * of irradiance E = 3 from μ0 = 0.8. Single scattering from a half-space
 * (Chandrasekhar): a point s along the view ray lies at depth s μ, its light
 * crosses s μ / μ0 of medium, so
 *   L = ∫ σ_s p E e^{-σ_t s (1 + μ/μ0)} ds = ω p E μ0 / (μ0 + μ),
 * independent of the density once the slab is optically thick. */
#define SLAB_MU0 0.8
static char *slab_scene(double scale, int spp)
{
    char *box = box_mesh(v3(-10, -10, -1), v3(10, 10, 0));
    char *s = sfmt("LookAt 0 0 5  0 0 0  0 1 0\n"
                   "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                   "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                   "Sampler \"zsobol\" \"integer pixelsamples\" %d\n"
                   "Integrator \"singlescatter\"\n"
                   "WorldBegin\n"
                   "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" "
                   "\"rgb sigma_a\" [0 0.5 1] \"rgb sigma_s\" [1 1 1] \"float scale\" %.17g\n"
                   "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [0 0.6 0.8] "
                   "\"point3 to\" [0 0 0]\n"
                   "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n"
                   "%sAttributeEnd\n",
                   spp, scale, box);
    free(box);
    return s;
}

static void test_dense_slab_closed_form(void **state)
{
    (void)state;
    const double scales[] = {1e2, 1e6, 1e9, 1e12};
    const rgb albedo = {1.0, 1.0 / 1.5, 0.5, 1.0 / 1.5};
    const int spp = 256;
    for (size_t k = 0; k < sizeof scales / sizeof scales[0]; ++k) {
        char *text = slab_scene(scales[k], spp);
        render_scene *rs = build(text);
        double t0 = now();
        pstat *px = image_stats(rs, 4, 4, spp);
        double secs = now() - t0;
        rgb mean, se;
        image_mean(px, 16, &mean, &se);
        for (int c = 0; c < 3; ++c) {
            double want = ch(albedo, c) / (4.0 * HZ_PI) * 3.0 * SLAB_MU0 / (SLAB_MU0 + 1.0);
            double z = (ch(mean, c) - want) / ch(se, c);
            note("dense slab scale %.0e channel %d: %.6g want %.6g (rel %+.4f, z %+.2f) %.2f s\n",
                 scales[k], c, ch(mean, c), want, ch(mean, c) / want - 1.0, z, secs);
            /* 4.5 standard errors, or 0.5% for the deterministic parts. */
            if (!(fabs(ch(mean, c) - want) <= 4.5 * ch(se, c) + 5e-3 * want)) {
                print_error("dense slab scale %g channel %d: got %.6g ± %.3g, want %.6g\n",
                            scales[k], c, ch(mean, c), ch(se, c), want);
                fail();
            }
        }
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}


/* HG at g = ±0.99999 on the same slab (scale 100): the closed form holds with
 * p(cos) evaluated in the far tail of the peak (g = 0.99999, light at μ0 =
 * 0.8: p ~ 2e-7) and on the backscattering peak itself (g = -0.99999, light
 * behind the camera: p = (1 + g)/(4π (1 - |g|)^2) ~ 1.6e9). test_media.c's
 * test_extreme_g covers every light kind and box.vdb at these g. */
static void test_extreme_g_slab(void **state)
{
    (void)state;
    const struct {
        double g, ly, lz;
    } cases[] = {{0.99999, 0.6, 0.8}, {-0.99999, 0.6, 0.8}, {-0.99999, 0.0, 1.0}};
    const rgb albedo = {1.0, 1.0 / 1.5, 0.5, 1.0 / 1.5};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *box = box_mesh(v3(-10, -10, -1), v3(10, 10, 0));
        char *text = sfmt("LookAt 0 0 5  0 0 0  0 1 0\n"
                          "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n"
                          "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
                          "Sampler \"zsobol\" \"integer pixelsamples\" 64\n"
                          "Integrator \"singlescatter\"\n"
                          "WorldBegin\n"
                          "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" "
                          "\"rgb sigma_a\" [0 0.5 1] \"rgb sigma_s\" [1 1 1] \"float scale\" 100 "
                          "\"float g\" %.17g\n"
                          "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [0 %.17g %.17g] "
                          "\"point3 to\" [0 0 0]\n"
                          "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n"
                          "%sAttributeEnd\n",
                          cases[k].g, cases[k].ly, cases[k].lz, box);
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 4, 4, 64);
        rgb mean, se;
        image_mean(px, 16, &mean, &se);
        double mu0 = cases[k].lz; /* wo = +z, wi = the light's direction */
        double p = hg(mu0, cases[k].g);
        for (int c = 0; c < 3; ++c) {
            double want = ch(albedo, c) * p * 3.0 * mu0 / (mu0 + 1.0);
            note("g %+.5f, light at mu0 %.1f, channel %d: %.7g want %.7g (rel %+.2e)\n",
                 cases[k].g, mu0, c, ch(mean, c), want, ch(mean, c) / want - 1.0);
            expect_close(ch(mean, c), want, 5e-3, 4.5 * ch(se, c), "extreme g slab", c, k);
        }
        free(px);
        render_scene_destroy(rs);
        free(text);
        free(box);
    }
}

/* The dense sphere of test_media.c's test_extreme_density (radius 1.2, lit
 * from the camera's side), where haze used to go dark (9% at scale 1e6, black
 * at 1e9): every pixel whose surface normal is within 60 degrees of both the
 * view and the light, against the half-space closed form ω p E μ0/(μ0 + μ). */
static void test_dense_sphere(void **state)
{
    (void)state;
    const double scales[] = {1e6, 1e9, 1e12};
    const rgb albedo = {1.0, 1.0 / 1.5, 0.5, 1.0 / 1.5};
    for (size_t k = 0; k < sizeof scales / sizeof scales[0]; ++k) {
        char *text = sfmt("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                          "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                          "Sampler \"zsobol\" \"integer pixelsamples\" 64\n"
                          "Integrator \"singlescatter\"\n"
                          "WorldBegin\n"
                          "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" "
                          "\"rgb sigma_a\" [0 0.5 1] \"rgb sigma_s\" [1 1 1] \"float scale\" %g\n"
                          "LightSource \"distant\" \"rgb L\" [3 3 3] \"point3 from\" [0 0 1] "
                          "\"point3 to\" [0 0 0]\n"
                          "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n"
                          "Shape \"sphere\" \"float radius\" 1.2\nAttributeEnd\n",
                          scales[k]);
        render_scene *rs = build(text);
        pstat *px = image_stats(rs, 8, 8, 64);
        /* got / want over the pixels: its mean and standard error */
        double sum = 0.0, var = 0.0;
        int n = 0;
        for (int i = 0; i < 64; ++i) {
            vec3 o, d;
            camera_ray_world(rs, i % 8 + 0.5, i / 8 + 0.5, &o, &d);
            double b = v3_dot(o, d), disc = b * b - (v3_length_sq(o) - 1.44);
            if (disc <= 0.0)
                continue;
            vec3 nrm = v3_scale(v3_add(o, v3_scale(d, -b - sqrt(disc))), 1.0 / 1.2);
            double mu = -v3_dot(nrm, d), mu0 = nrm.z;
            if (mu < 0.5 || mu0 < 0.5)
                continue;
            for (int c = 0; c < 3; ++c) {
                double want = ch(albedo, c) / (4.0 * HZ_PI) * 3.0 * mu0 / (mu0 + mu);
                sum += ch(px[i].mean, c) / want;
                var += pow(ch(px[i].se, c) / want, 2);
                ++n;
            }
        }
        double ratio = sum / n, se = sqrt(var) / n;
        note("dense sphere scale %.0e: got / closed form %.4f ± %.4f over %d pixel channels\n",
             scales[k], ratio, se, n);
        assert_true(n >= 60);
        expect_close(ratio, 1.0, 5e-3, 4.5 * se, "dense sphere got / want", scales[k], 0);
        free(px);
        render_scene_destroy(rs);
        free(text);
    }
}

/* A camera ray into box.vdb at density scale 1e12 with each estimator: it
 * must end (transmittance reaches 0, or Russian roulette ends it) and be
 * black: the sky behind is hidden. Times are reported: raymarch and jittered
 * take microseconds; ratio tracking against the majorant 2e12 takes ~1.6e6
 * tentative collisions to cross the one-voxel density ramp at the box's
 * boundary before the walk dies (~0.3 s in a Release build). */
static void test_dense_grid_ray_time(void **state)
{
    (void)state;
    const char *modes[] = {"raymarch", "jittered", "ratio"};
    for (int k = 0; k < 3; ++k) {
        char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
        char *text = sfmt("LookAt 0.484375 0.484375 4  0.484375 0.484375 0  0 1 0\n"
                          "Camera \"perspective\" \"float fov\" 8\n"
                          "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                          "Sampler \"independent\" \"integer pixelsamples\" 1\n"
                          "Integrator \"singlescatter\" \"string transmittance\" \"%s\"\n"
                          "WorldBegin\n"
                          "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                          "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                          "\"string filename\" \"%s/box.vdb\" \"rgb sigma_a\" [0.5 1 2] "
                          "\"rgb sigma_s\" [0 0 0] \"float scale\" 1e12\n"
                          "AttributeBegin\nMediumInterface \"box\" \"\"\nMaterial \"interface\"\n"
                          "%sAttributeEnd\n",
                          modes[k], VOLUMES, encl);
        render_scene *rs = build(text);
        double t0 = now();
        pstat p = pixel_stats_raw(rs, 4, 4, 1);
        double secs = now() - t0;
        note("dense grid camera ray, %s: %.3g s\n", modes[k], secs);
        assert_true(p.finite);
        assert_true(rgb_is_black(p.mean));
        assert_true(secs < 20.0); /* generous: sanitizer builds are ~10x slower */
        render_scene_destroy(rs);
        free(text);
        free(encl);
    }
}

/* A point light exactly on the camera ray through a pixel centre, in fog:
 * the in-scattered radiance along that very ray is infinite (∫ ds / s²), but
 * every sample is finite (the equiangular strategy is degenerate there and
 * only distance sampling is used) and the film counts no non-finite sample.
 * The pixel's mean and standard error are reported; a neighbouring ray
 * (passing 1 pixel away) matches the airlight quadrature. */
static void test_light_on_ray(void **state)
{
    (void)state;
    char *text = sfmt("LookAt 0 0 0  0 0 1  0 1 0\n"
                      "MediumInterface \"\" \"fog\"\n"
                      "Camera \"perspective\" \"float fov\" 10\n"
                      "Film \"rgb\" \"integer xresolution\" 5 \"integer yresolution\" 5\n"
                      "Sampler \"zsobol\" \"integer pixelsamples\" 256\n"
                      "Integrator \"singlescatter\"\n"
                      "WorldBegin\n"
                      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" "
                      "\"rgb sigma_a\" [0.1 0.1 0.1] \"rgb sigma_s\" [0.2 0.3 0.4]\n"
                      "LightSource \"point\" \"rgb I\" [5 5 5] \"point3 from\" [0 0 2]\n");
    render_scene *rs = build(text);
    vec3 o, d;
    camera_ray_world(rs, 2.5, 2.5, &o, &d);
    assert_true(fabs(d.x) < 1e-15 && fabs(d.y) < 1e-15); /* the ray meets the light */
    pstat *px = image_stats(rs, 5, 5, 256);
    pstat c = px[2 * 5 + 2];
    assert_true(c.min >= 0.0);
    note("point light on the ray: centre pixel %.4g ± %.3g (256 samples)\n", c.mean.r, c.se.r);
    camera_ray_world(rs, 3.5, 2.5, &o, &d);
    double want = airlight(0.2, 0.3, 0.0, 5.0, o, d, v3(0, 0, 2), INFINITY);
    note("point light on the ray: next pixel %.6g ± %.3g, quadrature %.6g\n", px[2 * 5 + 3].mean.r,
         px[2 * 5 + 3].se.r, want);
    expect_close(px[2 * 5 + 3].mean.r, want, 1e-2, 4.5 * px[2 * 5 + 3].se.r, "beside the light", 3,
                 2);
    free(px);
    /* The film: a full render (filtered pixels) counts no non-finite sample. */
    render_expect_finite(rs);
    render_scene_destroy(rs);
    free(text);
}

/* box.vdb (voxels of 1/32) and everything around it scaled by k = 32e-6 and
 * 32e6 (voxels of 1e-6 and 1e6 world units), densities by 1/k and the camera placed k times as far: the same
 * optical depths along the same rays, so the same image as at k = 1 (every
 * estimator uses the same random numbers: marching agrees to float rounding;
 * ratio and residual tracking too, except where rounding moves a tentative
 * collision that falls within rounding of a majorant-cell boundary into the
 * neighbouring cell, an equally valid sample with that cell's majorant: a
 * rare, small difference). */
static char *scaled_box_scene(double k, const char *mode)
{
    char *encl = box_mesh(v3(-0.1, -0.1, -0.1), v3(1.1, 1.1, 1.1));
    char *s = sfmt("LookAt %.17g %.17g %.17g  %.17g %.17g %.17g  0 1 0\n"
                   "Camera \"perspective\" \"float fov\" 20\n"
                   "Film \"rgb\" \"integer xresolution\" 6 \"integer yresolution\" 6\n"
                   "Sampler \"zsobol\" \"integer pixelsamples\" 4\n"
                   "Integrator \"singlescatter\" \"string transmittance\" \"%s\"\n"
                   "WorldBegin\n"
                   "LightSource \"infinite\" \"rgb L\" [0.3 0.3 0.3]\n"
                   "LightSource \"distant\" \"rgb L\" [2 2 2] \"point3 from\" [1 2 3] "
                   "\"point3 to\" [0 0 0]\n"
                   "Scale %.17g %.17g %.17g\n"
                   "MakeNamedMedium \"box\" \"string type\" \"nanovdb\" "
                   "\"string filename\" \"%s/box.vdb\" \"rgb sigma_a\" [0.5 1 2] "
                   "\"rgb sigma_s\" [1 1 1] \"float scale\" %.17g \"float g\" 0.3\n"
                   "AttributeBegin\nMediumInterface \"box\" \"\"\nMaterial \"interface\"\n"
                   "%sAttributeEnd\n",
                   0.8 * k, 0.9 * k, 3.0 * k, 0.5 * k, 0.5 * k, 0.5 * k, mode, k, k, k, VOLUMES,
                   1.0 / k, encl);
    free(encl);
    return s;
}

static void test_voxel_size_extremes(void **state)
{
    (void)state;
    const char *modes[] = {"raymarch", "jittered", "ratio", "residual"};
    for (int m = 0; m < 4; ++m) {
        char *t1 = scaled_box_scene(1.0, modes[m]);
        render_scene *r1 = build(t1);
        pstat *ref = image_stats(r1, 6, 6, 4);
        const double ks[] = {32e-6, 32e6};
        for (int j = 0; j < 2; ++j) {
            char *tk = scaled_box_scene(ks[j], modes[m]);
            render_scene *rk = build(tk);
            pstat *px = image_stats(rk, 6, 6, 4);
            double worst = 0.0;
            for (int i = 0; i < 36; ++i)
                for (int c = 0; c < 3; ++c) {
                    double a = ch(px[i].mean, c), b = ch(ref[i].mean, c);
                    worst = fmax(worst, fabs(a - b) / fmax(b, 1e-3));
                }
            note("voxel size %.0e (%s): worst relative difference %.3g\n", ks[j] / 32, modes[m],
                 worst);
            assert_true(worst < (m < 2 ? 1e-12 : 0.1));
            free(px);
            render_scene_destroy(rk);
            free(tk);
        }
        free(ref);
        render_scene_destroy(r1);
        free(t1);
    }
}

/* Rays grazing a medium's interface: the camera 1e-3 above the top face
 * y = 0 of an absorbing slab [-1e3, 1e3] x [-1, 0] x [-1e3, 1e3], looking
 * along it, a sky behind. Each pixel-centre ray enters the top at
 * t1 = 1e-3/|d.y| and leaves through the bottom or the far side: the pixel is
 * L e^{-σ (t2 - t1)} (exact but for float rounding), however close to the
 * horizon. */
static void test_grazing_interface(void **state)
{
    (void)state;
    char *box = box_mesh(v3(-1e3, -1, -1e3), v3(1e3, 0, 1e3));
    char *text = sfmt("LookAt 0 1e-3 0  0 1e-3 1  0 1 0\n"
                      "Camera \"perspective\" \"float fov\" 60\n"
                      "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                      "Sampler \"zsobol\" \"integer pixelsamples\" 1\n"
                      "Integrator \"singlescatter\"\n"
                      "WorldBegin\n"
                      "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                      "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" "
                      "\"rgb sigma_a\" [0.001 0.002 0.004] \"rgb sigma_s\" [0 0 0]\n"
                      "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n"
                      "%sAttributeEnd\n",
                      box);
    render_scene *rs = build(text);
    const double sigma[3] = {0.001, 0.002, 0.004};
    int below = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            vec3 o, d;
            camera_ray_world(rs, x + 0.5, y + 0.5, &o, &d);
            pixel_eval e = eval_pixel(rs, x + 0.5, y + 0.5, 1);
            double len = 0.0;
            if (d.y < 0.0) {
                double t1 = o.y / -d.y, t2 = (o.y + 1.0) / -d.y;
                double tx = (1e3 - fabs(o.x)) / fabs(d.x), tz = (1e3 - o.z) / d.z;
                len = fmax(fmin(fmin(t2, tx), tz) - t1, 0.0);
                ++below;
            }
            for (int c = 0; c < 3; ++c)
                expect_close(ch(e.L, c), exp(-sigma[c] * len), 1e-5, 0.0, "grazing slab", x, y);
        }
    assert_int_equal(below, 128);
    /* The film: no non-finite sample. */
    render_expect_finite(rs);
    render_scene_destroy(rs);
    free(text);
    free(box);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dense_slab_closed_form),
        cmocka_unit_test(test_dense_sphere),
        cmocka_unit_test(test_extreme_g_slab),
        cmocka_unit_test(test_dense_grid_ray_time),
        cmocka_unit_test(test_light_on_ray),
        cmocka_unit_test(test_voxel_size_extremes),
        cmocka_unit_test(test_grazing_interface),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
