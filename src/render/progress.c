#include "render/progress.h"

#include <math.h>

enum { BAR_WIDTH = 40 };

void progress_format_duration(double s, char *buf, size_t size)
{
    if (!isfinite(s) || s < 0)
        snprintf(buf, size, "--");
    else if (s < 60)
        snprintf(buf, size, "%.1fs", s);
    else if (s < 3600)
        snprintf(buf, size, "%dm%02ds", (int)(s / 60), (int)fmod(s, 60));
    else
        snprintf(buf, size, "%dh%02dm", (int)(s / 3600), (int)fmod(s / 60, 60));
}

static void draw(progress_bar *b, int done, double now)
{
    double frac = b->total > 0 ? (double)done / b->total : 1.0;
    int filled = (int)(frac * BAR_WIDTH);
    char bar[BAR_WIDTH + 1];
    for (int i = 0; i < BAR_WIDTH; ++i)
        bar[i] = i < filled ? '#' : '.';
    bar[BAR_WIDTH] = '\0';
    double elapsed = now - b->start;
    char el[32], eta[32];
    progress_format_duration(elapsed, el, sizeof el);
    progress_format_duration(done > 0 ? elapsed * (b->total - done) / done : NAN, eta, sizeof eta);
    fprintf(b->out, "\r[%s] %5.1f%%  %s elapsed  ETA %s ", bar, 100.0 * frac, el, eta);
    fflush(b->out);
    b->last_drawn = done;
    b->last_time = now;
}

void progress_begin(progress_bar *b, FILE *out, int total, double now)
{
    b->out = out;
    b->total = total;
    b->last_drawn = -1;
    b->start = b->last_time = now;
}

void progress_update(progress_bar *b, int done, double now)
{
    if (!b->out)
        return;
    /* Redraw on progress, and at least every second so the ETA stays alive. */
    if (done != b->last_drawn || now - b->last_time >= 1.0)
        draw(b, done, now);
}

void progress_end(progress_bar *b, int done, double now)
{
    if (!b->out)
        return;
    draw(b, done, now);
    fputc('\n', b->out);
}
