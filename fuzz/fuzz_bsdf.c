/* libFuzzer target: the measured-BRDF loader (materials/measured_data.h: the
 * tensor_file container, the BRDF's fields, shapes and values, its warps and
 * the spectra's reduction to RGB) on arbitrary bytes, through an in-memory
 * file (fuzz_memfd.h); a BRDF that loads is then evaluated, its pdf taken
 * and sampled at a few directions, and every value must be finite. */
#define _GNU_SOURCE
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#include "fuzz_memfd.h"
#include "materials/measured.h"

static void touch(const measured_brdf *m)
{
    const vec3 dirs[4] = {{0, 0, 1}, {0.6, 0, 0.8}, {-0.48, 0.6, 0.64}, {0, -0.99, 0.14106736}};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            rgb f = bxdf_measured_f(m, dirs[i], dirs[j]);
            double pdf = bxdf_measured_pdf(m, dirs[i], dirs[j]);
            bsdf_sample s;
            bool ok = bxdf_measured_sample(m, dirs[i], v2(0.05 + 0.3 * j, 0.9 - 0.2 * i), &s);
            if (!isfinite(f.r + f.g + f.b + pdf) || f.r < 0 || f.g < 0 || f.b < 0 || pdf < 0 ||
                (ok && !(isfinite(s.f.r + s.f.g + s.f.b + s.pdf) && s.pdf > 0)))
                abort();
        }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    int fd = fuzz_memfd("haze-fuzz-bsdf", data, size, path, sizeof path);
    measured_brdf *m = NULL;
    hz_error err;
    if (measured_brdf_read(path, &m, &err) == HZ_OK) {
        touch(m);
        measured_brdf_destroy(m);
    }
    close(fd);
    return 0;
}
