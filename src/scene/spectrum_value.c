#include "scene/spectrum_value.h"

#include <assert.h>

#include "scene/spectrum.h"

spectrum_value spectrum_value_rgb(rgb c, spectrum_use use)
{
    return (spectrum_value){.kind = SPECTRUM_VALUE_RGB, .use = use, .rgb = c, .scale = 1.0};
}

/* Piecewise linear through the samples, 0 outside them. */
static double sampled_at(const double *lambda, const double *value, size_t n, double l)
{
    if (n == 0 || !(l >= lambda[0] && l <= lambda[n - 1]))
        return 0.0;
    size_t lo = 0, hi = n - 1; /* lambda[lo] <= l <= lambda[hi] */
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (lambda[mid] <= l)
            lo = mid;
        else
            hi = mid;
    }
    if (hi == lo || value[lo] == value[hi])
        return value[lo]; /* exact on flat pieces: a constant stays itself */
    double t = (l - lambda[lo]) / (lambda[hi] - lambda[lo]);
    return hz_lerp(t, value[lo], value[hi]);
}

double spectrum_value_eval(const spectrum_value *s, double lambda)
{
    switch (s->kind) {
    case SPECTRUM_VALUE_BLACKBODY:
        return s->scale * spectrum_blackbody_at(lambda, s->kelvin);
    case SPECTRUM_VALUE_SAMPLED:
        return s->scale * sampled_at(s->lambda, s->value, s->n, lambda);
    case SPECTRUM_VALUE_RGB:
        break;
    }
    assert(!"spectrum_value_eval: an RGB value has no native spectrum");
    return 0.0;
}

bool spectrum_value_is_constant(const spectrum_value *s)
{
    switch (s->kind) {
    case SPECTRUM_VALUE_RGB:
        /* An emitter's RGB is a spectrum times the colour space's
         * illuminant (pbrt-v4's RGBIlluminantSpectrum): never flat. */
        return s->use != SPECTRUM_USE_ILLUMINANT && s->rgb.r == s->rgb.g && s->rgb.g == s->rgb.b;
    case SPECTRUM_VALUE_BLACKBODY:
        return false;
    case SPECTRUM_VALUE_SAMPLED:
        for (size_t i = 1; i < s->n; ++i)
            if (s->value[i] != s->value[0])
                return false;
        return s->n > 0;
    }
    return false;
}
