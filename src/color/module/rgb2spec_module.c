/* The RGB -> spectrum tables' module (color/rgb2spec_module.h): the tables
 * tools/rgb2spec_opt.c solved into the build tree, and the entry table that
 * points at them. */
#include "color/rgb2spec_module.h"

/* The generated source defines `const rgb2spec_table rgb2spec_tables[]`, one
 * solution per colour space: here that is an array of rgb2spec_solution,
 * private to the module, that the tables below point into. */
#define rgb2spec_table rgb2spec_solution
#define rgb2spec_tables rgb2spec_solutions
#include "rgb2spec_tables.c"
#undef rgb2spec_table
#undef rgb2spec_tables

static const rgb2spec_table tables[COLOR_SPACE_COUNT] = {
    {COLOR_SPACE_SRGB, &rgb2spec_solutions[COLOR_SPACE_SRGB]},
    {COLOR_SPACE_REC2020, &rgb2spec_solutions[COLOR_SPACE_REC2020]},
    {COLOR_SPACE_ACES2065_1, &rgb2spec_solutions[COLOR_SPACE_ACES2065_1]},
    {COLOR_SPACE_DCI_P3, &rgb2spec_solutions[COLOR_SPACE_DCI_P3]},
};

/* The one exported symbol (the module is built with hidden visibility). */
__attribute__((visibility("default"))) extern const haze_rgb2spec_api haze_rgb2spec_entry;
const haze_rgb2spec_api haze_rgb2spec_entry = {
    HAZE_RGB2SPEC_ABI, sizeof(haze_rgb2spec_api),     sizeof(rgb2spec_table),
    sizeof(rgb2spec_solution), COLOR_SPACE_COUNT, tables};
