#include "color/illuminant.h"

#include <assert.h>
#include <math.h>

illuminant illuminant_of_color_space(color_space cs)
{
    assert(cs >= 0 && cs < COLOR_SPACE_COUNT);
    return cs == COLOR_SPACE_ACES2065_1 ? ILLUMINANT_ACES_D60 : ILLUMINANT_D65;
}

double illuminant_raw(illuminant il, double lambda)
{
    assert(il >= 0 && il < ILLUMINANT_COUNT);
    const double *v = illuminant_table_5nm[il];
    double x = (lambda - ILLUMINANT_LAMBDA_MIN) / ILLUMINANT_LAMBDA_STEP;
    if (!(x > 0.0))
        return v[0];
    if (x >= ILLUMINANT_ROWS - 1)
        return v[ILLUMINANT_ROWS - 1];
    double fi = floor(x), t = x - fi;
    int i = (int)fi;
    return (1.0 - t) * v[i] + t * v[i + 1];
}
