#include "scene/named_spectra.h"

#include <string.h>

typedef struct {
    const char *name;
    double r, g, b;
} named;

/* Derived as named_spectra.h says; the reflectances they give at normal
 * incidence are in the comments. */
static const named spectra[] = {
    {"metal-Ag-eta", 0.12896, 0.12639, 0.14819},
    {"metal-Ag-k", 4.10355, 3.36834, 2.38363}, /* 0.972 0.960 0.915 */
    {"metal-Al-eta", 1.21488, 0.92067, 0.62943},
    {"metal-Al-k", 7.14568, 6.57458, 5.53805}, /* 0.913 0.922 0.924 */
    {"metal-Au-eta", 0.28205, 0.47926, 1.43461},
    {"metal-Au-k", 10.54402, 2.57485, 1.67697}, /* 0.990 (1.022 clamped) 0.783 0.343 */
    {"metal-Cu-eta", 0.43052, 0.96400, 1.16244},
    {"metal-Cu-k", 6.06186, 2.60415, 2.32192}, /* 0.956 0.638 0.538 */
    {"metal-CuZn-eta", 0.49243, 0.56483, 1.05988},
    {"metal-CuZn-k", 4.42455, 2.78339, 1.76010}, /* 0.910 0.778 0.422 */
    {"metal-MgO-eta", 1.73713, 1.74166, 1.75211},
    {"metal-MgO-k", 0.0, 0.0, 0.04125}, /* 0.072 0.073 0.075 */
    {"metal-TiO2-eta", 2.90938, 2.97236, 3.16038},
    {"metal-TiO2-k", 0.0, 0.0, 0.26887}, /* 0.232 0.245 0.273 */
    {"glass-BK7", 1.51854, 1.51854, 1.51854},
    {"glass-BAF10", 1.67305, 1.67305, 1.67305},
    {"glass-FK51A", 1.48780, 1.48780, 1.48780},
    {"glass-LASF9", 1.85581, 1.85581, 1.85581},
    {"glass-F5", 1.67709, 1.67709, 1.67709},
    {"glass-F10", 1.73357, 1.73357, 1.73357},
    {"glass-F11", 1.79112, 1.79112, 1.79112},
    {"stdillum-A", 1.84470, 0.82622, 0.23290},
    {"stdillum-D50", 1.08569, 0.99985, 0.74903},
    {"stdillum-D65", 0.99942, 1.00024, 0.99937},
    {"stdillum-F1", 0.99401, 1.02045, 0.81501},
    {"stdillum-F2", 1.38665, 0.94144, 0.44095},
    {"stdillum-F3", 1.63038, 0.88734, 0.25878},
    {"stdillum-F4", 1.86909, 0.82806, 0.14285},
    {"stdillum-F5", 0.95242, 1.03730, 0.77061},
    {"stdillum-F6", 1.36081, 0.95629, 0.36988},
    {"stdillum-F7", 1.04782, 0.99830, 0.87598},
    {"stdillum-F8", 1.23390, 0.96916, 0.61639},
    {"stdillum-F9", 1.43882, 0.92413, 0.45872},
    {"stdillum-F10", 1.28405, 0.95574, 0.60153},
    {"stdillum-F11", 1.54779, 0.89783, 0.39824},
    {"stdillum-F12", 1.92400, 0.81191, 0.14102},
};

bool named_spectrum_rgb(const char *name, rgb *out)
{
    for (size_t i = 0; i < sizeof spectra / sizeof spectra[0]; ++i)
        if (strcmp(spectra[i].name, name) == 0) {
            *out = rgb_make(spectra[i].r, spectra[i].g, spectra[i].b);
            return true;
        }
    return false;
}

const named_spectrum_samples *named_spectrum_find(const char *name)
{
    for (size_t i = 0; i < named_spectra_table_count; ++i)
        if (strcmp(named_spectra_table[i].name, name) == 0)
            return &named_spectra_table[i];
    return NULL;
}
