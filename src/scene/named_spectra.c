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
    {"stdillum-F1", 0.95382, 1.01963, 0.94154},
    {"stdillum-F2", 1.33951, 0.94331, 0.56129},
    {"stdillum-F3", 1.57575, 0.89140, 0.37956},
    {"stdillum-F4", 1.80553, 0.83454, 0.26589},
    {"stdillum-F5", 0.91499, 1.03655, 0.88833},
    {"stdillum-F6", 1.31555, 0.95813, 0.48506},
    {"stdillum-F7", 0.99994, 1.00050, 0.99525},
    {"stdillum-F8", 1.17631, 0.97599, 0.71838},
    {"stdillum-F9", 1.37640, 0.93168, 0.56782},
    {"stdillum-F10", 1.17686, 0.97598, 0.71682},
    {"stdillum-F11", 1.41131, 0.92509, 0.53023},
    {"stdillum-F12", 1.76755, 0.84543, 0.26991},
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
