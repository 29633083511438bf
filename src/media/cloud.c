#include "media/cloud.h"

#include "core/noise.h"

static float clampf(float v, float lo, float hi) { return v < lo ? lo : v > hi ? hi : v; }

double cloud_density(const cloud_params *c, vec3 p)
{
    float px = (float)p.x, py = (float)p.y, pz = (float)p.z;
    float x = c->frequency * px, y = c->frequency * py, z = c->frequency * pz;
    if (c->wispiness > 0.0f) {
        /* Wisps: the lookup point pushed along the noise's gradient. */
        float omega = 0.05f * c->wispiness, lambda = 10.0f;
        for (int i = 0; i < 2; ++i) {
            float qx = lambda * x, qy = lambda * y, qz = lambda * z, delta = 0.01f;
            float n = noise3(qx, qy, qz);
            float gx = (noise3(qx + delta, qy, qz) - n) / delta;
            float gy = (noise3(qx, qy + delta, qz) - n) / delta;
            float gz = (noise3(qx, qy, qz + delta) - n) / delta;
            x += omega * gx;
            y += omega * gy;
            z += omega * gz;
            omega *= 0.5f;
            lambda *= 1.99f;
        }
    }
    float d = 0.0f, omega = 0.5f, lambda = 1.0f;
    for (int i = 0; i < 5; ++i) {
        d += omega * noise3(lambda * x, lambda * y, lambda * z);
        omega *= 0.5f;
        lambda *= 1.99f;
    }
    d = clampf((1.0f - py) * 4.5f * c->density * d, 0.0f, 1.0f);
    d += 2.0f * (0.5f - py > 0.0f ? 0.5f - py : 0.0f);
    return clampf(d, 0.0f, 1.0f);
}
