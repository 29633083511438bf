/* Issue 45: a fog-filled room lit by a spot and two point lights, a thin
 * lens in the fog, volpath. At equal samples the low-discrepancy samplers
 * (zsobol, stratified) must be no noisier than independent sampling within
 * noise (10%), for maxdepth 1, 2, 4 and 16: the median over three seed
 * pairs of the relMSE between the pair's images (haze diff's, (a - b)^2 /
 * (|b| + 0.01)^2). After the fix: independent 0.030, 0.079, 0.089, 0.134;
 * zsobol 0.026, 0.058, 0.089, 0.123; stratified 0.020, 0.058, 0.085, 0.120.
 *
 * What made them noisier was not the samplers: light scattered near a point
 * light had unbounded variance (a scattering point at r from it adds 1 / r^2,
 * and distance sampling puts points within r with a density of r^3 only),
 * so each image was decided by its rarest samples. volpath now also samples
 * distances equiangularly toward point and spot lights in homogeneous media
 * (equiangular_ld). Before it, 32x24 at 64 spp: independent 0.079, 0.094,
 * 0.19, 0.20 at maxdepth 1, 2, 4, 16, zsobol 0.072, 0.098, 0.29, 0.22. */
#include "render_test_util.h"

enum { W = 32, H = 24, PAIRS = 3 };

static const char room[] =
    "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
    "    \"rgb sigma_a\" [0.02 0.02 0.02] \"rgb sigma_s\" [0.1 0.1 0.1] \"float g\" 0.3\n"
    "MediumInterface \"\" \"fog\"\n"
    "LookAt 0 1.5 -2.7   0 1.1 1   0 1 0\n"
    "Camera \"perspective\" \"float fov\" 60 \"float lensradius\" 0.02 "
    "\"float focaldistance\" 3.5\n"
    "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
    "Integrator \"volpath\" \"integer maxdepth\" %d\n"
    "%s\n"
    "WorldBegin\n"
    "MediumInterface \"\" \"\"\n"
    "Material \"diffuse\" \"rgb reflectance\" [0.6 0.6 0.6]\n"
    "Shape \"trianglemesh\"\n"
    "    \"integer indices\" [0 2 6  0 6 4  1 5 7  1 7 3  0 4 5  0 5 1\n"
    "                       2 3 7  2 7 6  0 1 3  0 3 2  4 6 7  4 7 5]\n"
    "    \"point3 P\" [-2 0 -3   2 0 -3  -2 3 -3   2 3 -3\n"
    "                -2 0  3   2 0  3  -2 3  3   2 3  3]\n"
    "AttributeBegin\n"
    "  Material \"diffuse\" \"rgb reflectance\" [0.7 0.3 0.2]\n"
    "  Translate -0.8 0.6 1.2\n"
    "  Shape \"sphere\" \"float radius\" 0.6\n"
    "AttributeEnd\n"
    "AttributeBegin\n"
    "  Material \"diffuse\" \"rgb reflectance\" [0.2 0.4 0.7]\n"
    "  Translate 0.9 0.5 1.8\n"
    "  Shape \"sphere\" \"float radius\" 0.5\n"
    "AttributeEnd\n"
    "LightSource \"spot\" \"point3 from\" [1.5 2.8 -2] \"point3 to\" [-0.8 0.6 1.2]\n"
    "    \"rgb I\" [60 66 78] \"float coneangle\" 15 \"float conedeltaangle\" 4\n"
    "LightSource \"point\" \"point3 from\" [-1.5 2.5 2.5] \"rgb I\" [8 7 6]\n"
    "LightSource \"point\" \"point3 from\" [1.2 0.4 -1] \"rgb I\" [3 3 4]\n";

static void render_room(const char *sampler, int maxdepth, uint64_t seed, rgb *out)
{
    char text[4096];
    snprintf(text, sizeof text, room, maxdepth, sampler);
    render_options opt = {.seed = seed, .color = RENDER_COLOR_RGB};
    render_scene *rs = build_scene_or_fail(text, &opt);
    render_expect_finite(rs);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            out[y * W + x] = film_get_pixel(render_scene_film(rs), x, y, 1.0);
    render_scene_destroy(rs);
}

static double rel_mse(const rgb *a, const rgb *b)
{
    double s = 0.0;
    for (int i = 0; i < W * H; ++i)
        for (int c = 0; c < 3; ++c) {
            double d = rgb_ch(a[i], c) - rgb_ch(b[i], c), r = fabs(rgb_ch(b[i], c)) + 0.01;
            s += d * d / (r * r);
        }
    return s / (3.0 * W * H);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median over PAIRS seed pairs of the pair's relMSE. */
static double median_pair_rel_mse(const char *sampler, int maxdepth)
{
    static rgb a[W * H], b[W * H];
    double e[PAIRS];
    for (int p = 0; p < PAIRS; ++p) {
        render_room(sampler, maxdepth, (uint64_t)(2 * p + 1), a);
        render_room(sampler, maxdepth, (uint64_t)(2 * p + 2), b);
        e[p] = rel_mse(a, b);
    }
    qsort(e, PAIRS, sizeof e[0], cmp_double);
    return e[PAIRS / 2];
}

static void test_low_discrepancy_no_noisier(void **state)
{
    (void)state;
    const int depths[4] = {1, 2, 4, 16};
    for (int k = 0; k < 4; ++k) {
        double ind = median_pair_rel_mse("Sampler \"independent\" \"integer pixelsamples\" 64",
                                         depths[k]);
        double zs = median_pair_rel_mse("Sampler \"zsobol\" \"integer pixelsamples\" 64",
                                        depths[k]);
        double st = median_pair_rel_mse(
            "Sampler \"stratified\" \"integer xsamples\" 8 \"integer ysamples\" 8", depths[k]);
        print_message("maxdepth %2d: relMSE independent %.4f, zsobol %.4f, stratified %.4f\n",
                      depths[k], ind, zs, st);
        /* "Within noise": 10% (before the fix zsobol was 50% above at
         * maxdepth 4, stratified 25% at maxdepth 2). */
        assert_true(zs <= 1.1 * ind);
        assert_true(st <= 1.1 * ind);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_low_discrepancy_no_noisier),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
