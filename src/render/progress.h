/* A one-line progress bar with elapsed time and ETA, redrawn in place. */
#ifndef HAZE_RENDER_PROGRESS_H
#define HAZE_RENDER_PROGRESS_H

#include <stdio.h>

typedef struct {
    FILE *out;          /* NULL: silent */
    int total;
    int last_drawn;
    double start, last_time;
} progress_bar;

void progress_begin(progress_bar *b, FILE *out, int total, double now);
void progress_update(progress_bar *b, int done, double now);
/* Draws the final state (`done` of total: less when interrupted) and ends the line. */
void progress_end(progress_bar *b, int done, double now);
/* "1m05s", "3.2s": used by the bar and the summary. */
void progress_format_duration(double seconds, char *buf, size_t size);

#endif
