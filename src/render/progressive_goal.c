#include "render/progressive_goal.h"

int progressive_pass_end(int begin, int spp)
{
    if (begin <= 0)
        return spp < 1 ? spp : 1;
    return begin <= spp / 2 ? 2 * begin : spp;
}

int progressive_first_end(const progressive_goal *goal, int spp)
{
    if (goal && goal->target_error > 0 && spp >= PROGRESSIVE_MIN_SPP)
        return PROGRESSIVE_MIN_SPP;
    return progressive_pass_end(0, spp);
}

bool progressive_pass_fits(double now, double deadline, double last_seconds, double last_work,
                           double work)
{
    if (!(last_work > 0.0))
        return now < deadline;
    return now + last_seconds * (work / last_work) <= deadline;
}

double progressive_noise_target(const progressive_goal *goal)
{
    double left = goal->target_error - goal->bias, least = 0.5 * goal->target_error;
    return left > least ? left : least; /* a NaN bias: the least */
}
