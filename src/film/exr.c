/* EXR through OpenEXRCore. Half <-> float conversion is done here rather
 * than by the library's pack/unpack routines so that the rounding (to
 * nearest, ties to even) is ours and testable, and the codec only ever moves
 * native-typed data. */
#define _POSIX_C_SOURCE 200809L

#include "film/exr.h"

#include "core/file.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <isa-l/igzip_lib.h>
#include <openexr.h>

#include "core/parallel.h"

/* ---- half floats ---------------------------------------------------- */

uint16_t exr_half_from_float(float f)
{
    uint32_t x;
    memcpy(&x, &f, sizeof x);
    uint32_t sign = (x >> 16) & 0x8000u;
    uint32_t a = x & 0x7fffffffu;
    if (a >= 0x7f800000u) /* inf, nan (keep a quiet nan) */
        return (uint16_t)(sign | 0x7c00u | (a > 0x7f800000u ? 0x200u | ((a >> 13) & 0x3ffu) : 0u));
    if (a >= 0x477ff000u) /* >= 65520 rounds to infinity */
        return (uint16_t)(sign | 0x7c00u);
    if (a < 0x38800000u) { /* below 2^-14: half subnormal, units of 2^-24 */
        if (a < 0x33000000u)
            return (uint16_t)sign;
        uint32_t e = a >> 23;
        uint32_t m = (a & 0x7fffffu) | 0x800000u;
        uint32_t shift = 126u - e; /* 14..24 */
        uint32_t q = m >> shift;
        uint32_t rem = m & ((1u << shift) - 1u);
        uint32_t halfway = 1u << (shift - 1u);
        if (rem > halfway || (rem == halfway && (q & 1u)))
            q++;
        return (uint16_t)(sign | q);
    }
    uint32_t h = (a - 0x38000000u) >> 13; /* rebias 127 -> 15 */
    uint32_t rem = a & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        h++; /* a carry into the exponent is the correct rounding */
    return (uint16_t)(sign | h);
}

float exr_half_to_float(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16;
    uint32_t e = (h >> 10) & 0x1fu;
    uint32_t m = h & 0x3ffu;
    uint32_t x;
    if (e == 0) {
        float v = (float)m * 5.9604644775390625e-8f; /* exact: m * 2^-24 */
        return sign ? -v : v;
    }
    if (e == 31)
        x = sign | 0x7f800000u | (m << 13);
    else
        x = sign | ((e + 112u) << 23) | (m << 13);
    float f;
    memcpy(&f, &x, sizeof f);
    return f;
}

/* ---- image helpers -------------------------------------------------- */

static hz_status exr_image_alloc_with(exr_image *img, int width, int height, int channel_count,
                                      bool pixels, hz_error *err)
{
    memset(img, 0, sizeof *img);
    if (width < 1 || height < 1 || channel_count < 1)
        return hz_fail(err, "exr: invalid image size %dx%d with %d channels", width, height,
                       channel_count);
    size_t n = (size_t)width * (size_t)height;
    img->channels = calloc((size_t)channel_count, sizeof *img->channels);
    if (!img->channels)
        return hz_fail(err, "exr: out of memory");
    img->channel_count = channel_count;
    img->width = width;
    img->height = height;
    img->display_width = width;
    img->display_height = height;
    for (int c = 0; c < channel_count && pixels; c++) {
        img->channels[c].pixels = calloc(n, sizeof(float));
        if (!img->channels[c].pixels) {
            exr_image_free(img);
            return hz_fail(err, "exr: out of memory for a %dx%d image (%zu MiB per channel)", width,
                           height, n * sizeof(float) >> 20);
        }
    }
    return HZ_OK;
}

hz_status exr_image_alloc(exr_image *img, int width, int height, int channel_count, hz_error *err)
{
    return exr_image_alloc_with(img, width, height, channel_count, true, err);
}

hz_status exr_image_alloc_lines(exr_image *img, int width, int height, int channel_count,
                                hz_error *err)
{
    return exr_image_alloc_with(img, width, height, channel_count, false, err);
}

void exr_image_free(exr_image *img)
{
    if (!img)
        return;
    for (int c = 0; c < img->channel_count; c++)
        free(img->channels[c].pixels);
    free(img->channels);
    free(img->attribute_names);
    free(img->attribute_values);
    memset(img, 0, sizeof *img);
}

const exr_channel *exr_find_channel(const exr_image *img, const char *name)
{
    for (int c = 0; c < img->channel_count; c++)
        if (strcmp(img->channels[c].name, name) == 0)
            return &img->channels[c];
    return NULL;
}

hz_status exr_image_add_attribute(exr_image *img, const char *name, const char *value, hz_error *err)
{
    if (!name[0] || strlen(name) >= sizeof img->attribute_names[0] ||
        strlen(value) >= sizeof img->attribute_values[0])
        return hz_fail(err, "exr: attribute \"%s\" name or value too long", name);
    int n = img->attribute_count + 1;
    char(*names)[64] = realloc(img->attribute_names, (size_t)n * sizeof *names);
    if (!names)
        return hz_fail(err, "exr: out of memory");
    img->attribute_names = names;
    char(*values)[EXR_ATTRIBUTE_VALUE_SIZE] =
        realloc(img->attribute_values, (size_t)n * sizeof *values);
    if (!values)
        return hz_fail(err, "exr: out of memory");
    img->attribute_values = values;
    snprintf(names[n - 1], sizeof names[n - 1], "%s", name);
    snprintf(values[n - 1], sizeof values[n - 1], "%s", value);
    img->attribute_count = n;
    return HZ_OK;
}

/* ---- context plumbing ----------------------------------------------- */

/* Per-call state: the temporary file a write goes to, and the first
 * detailed message from the library (no message ever goes to stderr). */
typedef struct {
    int fd;             /* write: the temporary file */
    char message[512];  /* first detailed message from the library */
} exr_io;

/* The exr_io of the context this thread is using, for the error handler.
 * The handler must never call back into the context: OpenEXRCore reports the
 * errors of a context in write mode (exr_write_header's failed write among
 * them) with the context's mutex held, and exr_get_user_data takes that same
 * non-recursive mutex, so a full disk hung haze forever (issue 42). A
 * thread-local needs no lock and is seen only by the thread whose call
 * failed, which is the thread OpenEXRCore reports on. The chunk workers set
 * none: their failures come back as result codes. */
static _Thread_local exr_io *exr_thread_io;

static void exr_error_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt; /* see exr_thread_io */
    exr_io *io = exr_thread_io;
    if (io && !io->message[0])
        snprintf(io->message, sizeof io->message, "%s", msg ? msg : exr_get_default_error_message(code));
}

/* Makes `io` the handler's for this thread's calls until exr_io_leave,
 * returning the one it replaces. */
static exr_io *exr_io_enter(exr_io *io)
{
    exr_io *old = exr_thread_io;
    exr_thread_io = io;
    return old;
}

static void exr_io_leave(exr_io *old) { exr_thread_io = old; }

static int64_t exr_write_fd(exr_const_context_t ctxt, void *userdata, const void *buffer, uint64_t sz,
                            uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_io *io = userdata;
    const char *p = buffer;
    uint64_t done = 0;
    while (done < sz) {
        ssize_t n = pwrite(io->fd, p + done, (size_t)(sz - done), (off_t)(offset + done));
        if (n < 0) {
            if (errno == EINTR)
                continue;
            /* Kept here first: the reason is errno's, whatever the library
             * makes of the failure. */
            const char *why = strerror(errno);
            if (!io->message[0])
                snprintf(io->message, sizeof io->message, "write failed: %s", why);
            error_cb(ctxt, EXR_ERR_WRITE_IO, "write failed: %s", why);
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static hz_status exr_fail_code(hz_error *err, const char *path, const char *what, exr_result_t rv,
                               const exr_io *io)
{
    return hz_fail(err, "%s: cannot %s EXR: %s", path, what,
                   io->message[0] ? io->message : exr_get_default_error_message(rv));
}

/* ---- writing -------------------------------------------------------- */

static int cmp_channel_name(const void *a, const void *b)
{
    const exr_channel *const *ca = a, *const *cb = b;
    return strcmp((*ca)->name, (*cb)->name);
}

static hz_status exr_validate(const char *path, const exr_image *img, hz_error *err)
{
    if (img->width < 1 || img->height < 1 || img->channel_count < 1 || !img->channels)
        return hz_fail(err, "%s: cannot write an empty EXR image (%dx%d, %d channels)", path,
                       img->width, img->height, img->channel_count);
    if (img->display_width < 1 || img->display_height < 1)
        return hz_fail(err, "%s: invalid EXR display window %dx%d", path, img->display_width,
                       img->display_height);
    if ((int64_t)img->data_x0 + img->width - 1 > INT32_MAX ||
        (int64_t)img->data_y0 + img->height - 1 > INT32_MAX)
        return hz_fail(err, "%s: EXR data window out of range", path);
    for (int c = 0; c < img->channel_count; c++) {
        const exr_channel *ch = &img->channels[c];
        if (!ch->name[0] || !memchr(ch->name, 0, sizeof ch->name) || (!ch->pixels && !img->fill))
            return hz_fail(err, "%s: EXR channel %d has no name or no pixels", path, c);
        for (int d = 0; d < c; d++)
            if (strcmp(ch->name, img->channels[d].name) == 0)
                return hz_fail(err, "%s: EXR channel \"%s\" appears twice", path, ch->name);
    }
    return HZ_OK;
}

/* ---- chunks: packed and compressed in parallel, written in order ---- */

/* One scanline chunk: where it lies, and its bytes once compressed. */
typedef struct {
    exr_chunk_info_t info;
    void *bytes;
    uint64_t size;
} exr_chunk_out;

typedef struct {
    exr_context_t ctx;
    int part;
    const exr_image *img;
    const exr_channel **sorted; /* in the file's channel order */
    uint16_t **halfs;           /* half copies of half channels */
    int lines;                  /* scanlines per chunk */
    exr_chunk_out *chunks;
    int chunk_count;
    atomic_int next;    /* the next chunk a worker takes */
    atomic_int failure; /* the first error (EXR_ERR_SUCCESS: none) */
} exr_chunk_job;

/* A worker's ZIP state: the compressor's work memory and the reordered
 * bytes of a chunk. */
typedef struct {
    uint8_t *level_buf; /* igzip's hash tables for EXR_ZIP_LEVEL */
    uint8_t *scratch;
    size_t scratch_size;
    exr_chunk_out *out; /* the chunk being compressed */
} exr_zip_worker;

/* igzip (ISA-L) level of the ZIP chunks: 2 compresses rendered images 3.5-7x
 * faster than libdeflate's 6 (long runs of black cost it almost nothing) for
 * files 3-7% larger (docs/performance.md). */
enum { EXR_ZIP_LEVEL = 2, EXR_ZIP_LEVEL_BUF = ISAL_DEF_LVL2_DEFAULT };

/* One zlib stream of the n bytes at in, into out (room for n bytes): its
 * size, or 0 when it would not be smaller than n. */
static size_t exr_zlib_stream(exr_zip_worker *w, uint8_t *in, size_t n, uint8_t *out)
{
    if (n > UINT32_MAX)
        return 0;
    struct isal_zstream z;
    memset(&z, 0, sizeof z); /* the init leaves state its assembly reads */
    isal_deflate_stateless_init(&z);
    z.level = EXR_ZIP_LEVEL;
    z.level_buf = w->level_buf;
    z.level_buf_size = EXR_ZIP_LEVEL_BUF;
    z.gzip_flag = IGZIP_ZLIB;
    z.next_in = in;
    z.avail_in = (uint32_t)n;
    z.next_out = out;
    z.avail_out = (uint32_t)n;
    z.flush = NO_FLUSH;
    z.end_of_stream = 1;
    /* STATELESS_OVERFLOW: it did not fit in n bytes. */
    return isal_deflate_stateless(&z) == COMP_OK && z.total_out < n ? z.total_out : 0;
}

/* The pipeline's compress step, for ZIP: OpenEXR's byte split (the even
 * bytes, then the odd ones) and delta predictor over the packed chunk, then
 * one zlib stream, kept for the ordered write. A chunk that does not shrink
 * is stored raw, which readers recognise by its size. */
static exr_result_t exr_zip_chunk(exr_encode_pipeline_t *enc)
{
    exr_zip_worker *w = enc->encoding_user_data;
    size_t n = (size_t)enc->packed_bytes;
    const uint8_t *raw = enc->packed_buffer;
    assert(n > 0); /* OpenEXRCore compresses only non-empty chunks */
    if (w->scratch_size < n) {
        free(w->scratch);
        w->scratch_size = 0;
        if (!(w->scratch = malloc(n)))
            return EXR_ERR_OUT_OF_MEMORY;
        w->scratch_size = n;
    }
    /* byte i of each half minus the byte before it in the split order, in
     * one pass over the packed bytes */
    size_t half = (n + 1) / 2;
    uint8_t *even = w->scratch, *odd = w->scratch + half;
    even[0] = raw[0];
    for (size_t j = 1; j < half; j++)
        even[j] = (uint8_t)(raw[2 * j] - raw[2 * j - 2] + 128);
    if (n > 1)
        odd[0] = (uint8_t)(raw[1] - raw[2 * half - 2] + 128);
    for (size_t j = 1; j < n - half; j++)
        odd[j] = (uint8_t)(raw[2 * j + 1] - raw[2 * j - 1] + 128);
    exr_chunk_out *out = w->out;
    if (!(out->bytes = malloc(n)))
        return EXR_ERR_OUT_OF_MEMORY;
    size_t size = exr_zlib_stream(w, w->scratch, n, out->bytes);
    if (size == 0) {
        memcpy(out->bytes, raw, n);
        size = n;
    }
    out->size = size;
    enc->compressed_bytes = size;
    return EXR_ERR_SUCCESS;
}

/* A worker's lines of chunk k for exr_image.fill: per channel of the
 * image (in its own order), lines x width floats, and their halfs for half
 * channels. */
typedef struct {
    float *lines;
    uint16_t *halfs;
    float **rows; /* per channel: its part of `lines` */
} exr_chunk_lines;

static void exr_chunk_lines_free(exr_chunk_lines *cl)
{
    free(cl->lines);
    free(cl->halfs);
    free(cl->rows);
}

static exr_result_t exr_chunk_lines_init(const exr_chunk_job *job, exr_chunk_lines *cl)
{
    const exr_image *img = job->img;
    size_t n = (size_t)job->lines * (size_t)img->width, nc = (size_t)img->channel_count;
    cl->lines = malloc(nc * n * sizeof *cl->lines);
    cl->halfs = malloc(nc * n * sizeof *cl->halfs);
    cl->rows = malloc(nc * sizeof *cl->rows);
    if (!cl->lines || !cl->halfs || !cl->rows)
        return EXR_ERR_OUT_OF_MEMORY;
    for (size_t c = 0; c < nc; c++)
        cl->rows[c] = cl->lines + c * n;
    return EXR_ERR_SUCCESS;
}

/* Points the pipeline's channels at chunk k's first line: in the image, or
 * (cl not NULL) in cl, filled now. */
static exr_result_t exr_chunk_channels(const exr_chunk_job *job, exr_encode_pipeline_t *enc, int k,
                                       exr_chunk_lines *cl)
{
    const exr_image *img = job->img;
    size_t off = (size_t)k * (size_t)job->lines * (size_t)img->width;
    if (cl) {
        int y0 = k * job->lines;
        int y1 = y0 + job->lines < img->height ? y0 + job->lines : img->height;
        img->fill(img->fill_ctx, y0, y1, cl->rows);
        off = 0;
    }
    for (int16_t i = 0; i < enc->channel_count; i++) {
        exr_coding_channel_info_t *cc = &enc->channels[i];
        int c = 0;
        while (c < img->channel_count && strcmp(job->sorted[c]->name, cc->channel_name) != 0)
            c++;
        if (c == img->channel_count) /* cannot happen: we declared every channel */
            return EXR_ERR_INVALID_ARGUMENT;
        /* the image's own index of the channel */
        const float *pixels = cl ? cl->rows[job->sorted[c] - img->channels] : job->sorted[c]->pixels;
        if (job->sorted[c]->half) {
            const uint16_t *h;
            if (cl) {
                size_t n = (size_t)enc->chunk.height * (size_t)img->width;
                uint16_t *o = cl->halfs + (size_t)c * (size_t)job->lines * (size_t)img->width;
                for (size_t j = 0; j < n; j++)
                    o[j] = exr_half_from_float(pixels[j]);
                h = o;
            } else {
                h = job->halfs[c] + off;
            }
            cc->encode_from_ptr = (const uint8_t *)h;
            cc->user_bytes_per_element = 2;
            cc->user_data_type = EXR_PIXEL_HALF;
        } else {
            cc->encode_from_ptr = (const uint8_t *)(pixels + off);
            cc->user_bytes_per_element = 4;
            cc->user_data_type = EXR_PIXEL_FLOAT;
        }
        cc->user_pixel_stride = cc->user_bytes_per_element;
        cc->user_line_stride = cc->user_bytes_per_element * img->width;
    }
    return EXR_ERR_SUCCESS;
}

/* A worker: packs and compresses the chunks it takes, with a pipeline of its
 * own (OpenEXRCore reads only the context while encoding). */
static void *exr_chunk_worker(void *arg)
{
    exr_chunk_job *job = arg;
    exr_encode_pipeline_t enc;
    bool ready = false;
    exr_zip_worker zip = {.level_buf = malloc(EXR_ZIP_LEVEL_BUF)};
    exr_result_t rv = zip.level_buf ? EXR_ERR_SUCCESS : EXR_ERR_OUT_OF_MEMORY;
    exr_chunk_lines lines = {NULL, NULL, NULL};
    if (rv == EXR_ERR_SUCCESS && job->img->fill)
        rv = exr_chunk_lines_init(job, &lines);
    for (int k; rv == EXR_ERR_SUCCESS && atomic_load(&job->failure) == EXR_ERR_SUCCESS &&
                (k = atomic_fetch_add(&job->next, 1)) < job->chunk_count;) {
        exr_chunk_out *out = &job->chunks[k];
        rv = ready ? exr_encoding_update(job->ctx, job->part, &out->info, &enc)
                   : exr_encoding_initialize(job->ctx, job->part, &out->info, &enc);
        if (rv)
            break;
        bool first = !ready;
        ready = true;
        if ((rv = exr_chunk_channels(job, &enc, k, job->img->fill ? &lines : NULL)))
            break;
        if (first) {
            if ((rv = exr_encoding_choose_default_routines(job->ctx, job->part, &enc)))
                break;
            enc.compress_fn = exr_zip_chunk;
            enc.yield_until_ready_fn = NULL; /* the order is kept by the writer */
            enc.write_fn = NULL;              /* exr_zip_chunk kept the bytes */
        }
        zip.out = out;
        enc.encoding_user_data = &zip;
        rv = exr_encoding_run(job->ctx, job->part, &enc);
        if (rv == EXR_ERR_SUCCESS && !out->bytes) /* an empty chunk: cannot happen */
            rv = EXR_ERR_INVALID_ARGUMENT;
    }
    if (ready)
        exr_encoding_destroy(job->ctx, &enc);
    free(zip.level_buf);
    free(zip.scratch);
    exr_chunk_lines_free(&lines);
    if (rv) {
        int none = EXR_ERR_SUCCESS;
        atomic_compare_exchange_strong(&job->failure, &none, (int)rv);
    }
    return NULL;
}

/* Every chunk of the image: compressed by up to img->threads workers (the
 * calling thread among them), then written in increasing y. */
static exr_result_t exr_write_chunks(exr_context_t ctx, int part, const exr_image *img,
                                     const exr_channel **sorted, uint16_t **halfs, int lines)
{
    int count = (img->height + lines - 1) / lines;
    exr_chunk_job job = {.ctx = ctx, .part = part, .img = img, .sorted = sorted,
                         .halfs = halfs, .lines = lines, .chunk_count = count};
    atomic_init(&job.next, 0);
    atomic_init(&job.failure, EXR_ERR_SUCCESS);
    job.chunks = calloc((size_t)count, sizeof *job.chunks);
    if (!job.chunks)
        return EXR_ERR_OUT_OF_MEMORY;
    exr_result_t rv = EXR_ERR_SUCCESS;
    for (int k = 0; k < count && !rv; k++)
        rv = exr_write_scanline_chunk_info(ctx, part, img->data_y0 + k * lines,
                                           &job.chunks[k].info);
    if (!rv) {
        int threads = img->threads < 1 ? 1 : img->threads;
        if (threads > EXR_MAX_WRITE_THREADS)
            threads = EXR_MAX_WRITE_THREADS;
        if (threads > count)
            threads = count;
        hz_parallel_run(threads, exr_chunk_worker, &job); /* failures in job.failure */
        rv = atomic_load(&job.failure);
    }
    for (int k = 0; k < count && !rv; k++)
        rv = exr_write_scanline_chunk(ctx, part, job.chunks[k].info.start_y, job.chunks[k].bytes,
                                      job.chunks[k].size);
    for (int k = 0; k < count; k++)
        free(job.chunks[k].bytes);
    free(job.chunks);
    return rv;
}

/* The file being written: its OpenEXRCore context and part, and what its
 * messages name. */
typedef struct {
    exr_context_t ctx;
    int part;
    const char *path;
    const exr_io *io;
} exr_writer;

/* One scanline part of the image's windows, ZIP compressed. */
static hz_status exr_add_image_part(exr_writer *w, const exr_image *img, hz_error *err)
{
    exr_attr_box2i_t dispw, dataw;
    exr_attr_v2f_t swc;
    dispw.min.x = 0;
    dispw.min.y = 0;
    dispw.max.x = img->display_width - 1;
    dispw.max.y = img->display_height - 1;
    dataw.min.x = img->data_x0;
    dataw.min.y = img->data_y0;
    dataw.max.x = img->data_x0 + img->width - 1;
    dataw.max.y = img->data_y0 + img->height - 1;
    swc.x = 0.f;
    swc.y = 0.f;
    exr_result_t rv;
    if ((rv = exr_add_part(w->ctx, NULL, EXR_STORAGE_SCANLINE, &w->part)) ||
        (rv = exr_initialize_required_attr(w->ctx, w->part, &dispw, &dataw, 1.f, &swc, 1.f,
                                           EXR_LINEORDER_INCREASING_Y, EXR_COMPRESSION_ZIP)))
        return exr_fail_code(err, w->path, "set up", rv, w->io);
    return HZ_OK;
}

/* The channels in `sorted` order. Without img->fill, half channels are
 * converted up front into halfs[c] (img->fill converts them a chunk at a
 * time). */
static hz_status exr_add_channels(const exr_writer *w, const exr_image *img,
                                  const exr_channel **sorted, uint16_t **halfs, hz_error *err)
{
    size_t npix = (size_t)img->width * (size_t)img->height;
    for (int c = 0; c < img->channel_count; c++) {
        exr_result_t rv = exr_add_channel(w->ctx, w->part, sorted[c]->name,
                                          sorted[c]->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                                          EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        if (rv)
            return exr_fail_code(err, w->path, "add a channel to", rv, w->io);
        if (sorted[c]->half && !img->fill) {
            halfs[c] = malloc(npix * sizeof(uint16_t));
            if (!halfs[c])
                return hz_fail(err, "exr: out of memory");
            for (size_t i = 0; i < npix; i++)
                halfs[c][i] = exr_half_from_float(sorted[c]->pixels[i]);
        }
    }
    return HZ_OK;
}

/* The image's string attributes, then its chromaticities if it has them. */
static hz_status exr_add_attributes(const exr_writer *w, const exr_image *img, hz_error *err)
{
    exr_result_t rv;
    for (int a = 0; a < img->attribute_count; a++) {
        if ((rv = exr_attr_set_string(w->ctx, w->part, img->attribute_names[a],
                                      img->attribute_values[a])))
            return exr_fail_code(err, w->path, "set an attribute of", rv, w->io);
    }
    if (img->has_chromaticities) {
        const float *c = img->chromaticities;
        exr_attr_chromaticities_t ch = {c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]};
        if ((rv = exr_attr_set_chromaticities(w->ctx, w->part, "chromaticities", &ch)))
            return exr_fail_code(err, w->path, "set the chromaticities of", rv, w->io);
    }
    return HZ_OK;
}

/* The header, then every chunk of pixels. */
static hz_status exr_write_header_and_pixels(const exr_writer *w, const exr_image *img,
                                             const exr_channel **sorted, uint16_t **halfs,
                                             hz_error *err)
{
    exr_result_t rv;
    if ((rv = exr_write_header(w->ctx)))
        return exr_fail_code(err, w->path, "write the header of", rv, w->io);
    int32_t lines = 1;
    if ((rv = exr_get_scanlines_per_chunk(w->ctx, w->part, &lines)) || lines < 1)
        return exr_fail_code(err, w->path, "write", rv, w->io);
    rv = exr_write_chunks(w->ctx, w->part, img, sorted, halfs, lines);
    if (rv)
        return exr_fail_code(err, w->path, "write pixels of", rv, w->io);
    return HZ_OK;
}

/* Everything of the file but the chunk offset table (exr_finish's). */
static hz_status exr_write_parts(exr_writer *w, const exr_image *img, const exr_channel **sorted,
                                 uint16_t **halfs, hz_error *err)
{
    for (int c = 0; c < img->channel_count; c++)
        sorted[c] = &img->channels[c];
    qsort(sorted, (size_t)img->channel_count, sizeof *sorted, cmp_channel_name);
    if (exr_add_image_part(w, img, err) != HZ_OK ||
        exr_add_channels(w, img, sorted, halfs, err) != HZ_OK ||
        exr_add_attributes(w, img, err) != HZ_OK)
        return HZ_ERROR;
    return exr_write_header_and_pixels(w, img, sorted, halfs, err);
}

/* Writes the whole file into io->fd. The channels are written in the order
 * OpenEXRCore keeps them (by name); half channels are converted into
 * buffers of their own. */
static hz_status exr_write_context(const char *path, const char *tmp, const exr_image *img,
                                   exr_io *io, hz_error *err)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_error_handler;
    init.write_fn = exr_write_fd;
    init.user_data = io;
    exr_writer w = {.ctx = NULL, .part = 0, .path = path, .io = io};
    exr_result_t rv = exr_start_write(&w.ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail_code(err, path, "start writing", rv, io);

    int nc = img->channel_count;
    const exr_channel **sorted = calloc((size_t)nc, sizeof *sorted);
    uint16_t **halfs = calloc((size_t)nc, sizeof *halfs);
    hz_status st = !sorted || !halfs ? hz_fail(err, "exr: out of memory")
                                     : exr_write_parts(&w, img, sorted, halfs, err);
    rv = exr_finish(&w.ctx); /* writes the chunk offset table */
    if (st == HZ_OK && rv != EXR_ERR_SUCCESS)
        st = exr_fail_code(err, path, "finish", rv, io);
    if (halfs)
        for (int c = 0; c < nc; c++)
            free(halfs[c]);
    free(halfs);
    free(sorted);
    return st;
}

void tmp_file_note_set(tmp_file_note *note, const char *tmp)
{
    if (!note)
        return;
    note->valid = 0;
    atomic_signal_fence(memory_order_seq_cst);
    snprintf(note->path, sizeof note->path, "%s", tmp);
    atomic_signal_fence(memory_order_seq_cst);
    note->valid = strlen(tmp) < sizeof note->path; /* a truncated name is never unlinked */
}

void tmp_file_note_clear(tmp_file_note *note)
{
    if (note)
        note->valid = 0;
    atomic_signal_fence(memory_order_seq_cst);
}

hz_status exr_write(const char *path, const exr_image *img, hz_error *err)
{
    return exr_write_noted(path, img, NULL, err);
}

hz_status exr_write_noted(const char *path, const exr_image *img, tmp_file_note *note,
                          hz_error *err)
{
    if (exr_validate(path, img, err) != HZ_OK)
        return HZ_ERROR;
    size_t len = strlen(path);
    char *tmp = malloc(len + 16);
    if (!tmp)
        return hz_fail(err, "exr: out of memory");
    memcpy(tmp, path, len);
    memcpy(tmp + len, ".tmp-XXXXXX", 12);
    exr_io io = {.fd = mkstemp(tmp)};
    if (io.fd < 0) {
        hz_status st = hz_fail(err, "%s: cannot create a temporary file next to it: %s", path,
                               strerror(errno));
        free(tmp);
        return st;
    }
    tmp_file_note_set(note, tmp);
    /* mkstemp makes the file private; give it the mode of the file it
     * replaces, or an ordinary image's. */
    struct stat old;
    mode_t mode = stat(path, &old) == 0 ? (old.st_mode & 07777) : 0644;
    hz_status st = HZ_OK;
    if (fchmod(io.fd, mode) != 0)
        st = hz_fail(err, "%s: cannot set permissions: %s", path, strerror(errno));
    if (st == HZ_OK) {
        exr_io *outer = exr_io_enter(&io);
        st = exr_write_context(path, tmp, img, &io, err);
        exr_io_leave(outer);
    }
    if (st == HZ_OK && fsync(io.fd) != 0)
        st = hz_fail(err, "%s: cannot flush EXR to disk: %s", path, strerror(errno));
    if (close(io.fd) != 0 && st == HZ_OK)
        st = hz_fail(err, "%s: cannot close EXR: %s", path, strerror(errno));
    if (st == HZ_OK && rename(tmp, path) != 0)
        st = hz_fail(err, "%s: cannot rename the temporary EXR into place: %s", path, strerror(errno));
    if (st != HZ_OK)
        unlink(tmp);
    tmp_file_note_clear(note);
    free(tmp);
    return st;
}

/* ---- reading -------------------------------------------------------- */

/* Where decoded data goes: float channels straight into the image, half
 * channels into a staging buffer converted at the end. */
typedef struct {
    exr_image *img;
    uint16_t **halfs;
} exr_read_target;

static exr_result_t exr_decode_chunk(exr_context_t ctx, const exr_chunk_info_t *ci, int x0, int y0,
                                     exr_read_target *t, exr_decode_pipeline_t *dec, bool *dec_init)
{
    exr_image *img = t->img;
    if (x0 < 0 || y0 < 0 || ci->width < 1 || ci->height < 1 || x0 + ci->width > img->width ||
        y0 + ci->height > img->height)
        return EXR_ERR_BAD_CHUNK_LEADER;
    exr_result_t rv = *dec_init ? exr_decoding_update(ctx, 0, ci, dec)
                                : exr_decoding_initialize(ctx, 0, ci, dec);
    if (rv)
        return rv;
    bool first = !*dec_init;
    *dec_init = true;
    for (int16_t k = 0; k < dec->channel_count; k++) {
        exr_coding_channel_info_t *cc = &dec->channels[k];
        int c = 0;
        while (c < img->channel_count && strcmp(img->channels[c].name, cc->channel_name) != 0)
            c++;
        if (c == img->channel_count)
            return EXR_ERR_INVALID_ARGUMENT;
        size_t off = (size_t)y0 * (size_t)img->width + (size_t)x0;
        if (img->channels[c].half) {
            cc->decode_to_ptr = (uint8_t *)(t->halfs[c] + off);
            cc->user_bytes_per_element = 2;
            cc->user_data_type = EXR_PIXEL_HALF;
        } else {
            cc->decode_to_ptr = (uint8_t *)(img->channels[c].pixels + off);
            cc->user_bytes_per_element = 4;
            cc->user_data_type = EXR_PIXEL_FLOAT;
        }
        cc->user_pixel_stride = cc->user_bytes_per_element;
        cc->user_line_stride = cc->user_bytes_per_element * img->width;
    }
    if (first && (rv = exr_decoding_choose_default_routines(ctx, 0, dec)))
        return rv;
    return exr_decoding_run(ctx, 0, dec);
}

static exr_result_t exr_read_pixels(exr_context_t ctx, exr_storage_t storage, exr_attr_box2i_t dw,
                                    exr_read_target *t)
{
    exr_decode_pipeline_t dec;
    memset(&dec, 0, sizeof dec);
    bool dec_init = false;
    exr_result_t rv = EXR_ERR_SUCCESS;
    exr_chunk_info_t ci;
    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines = 1;
        if ((rv = exr_get_scanlines_per_chunk(ctx, 0, &lines)))
            return rv;
        if (lines < 1)
            return EXR_ERR_INVALID_ATTR;
        for (int64_t y = dw.min.y; y <= dw.max.y && !rv; y += lines) {
            if ((rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &ci)))
                break;
            rv = exr_decode_chunk(ctx, &ci, 0, ci.start_y - dw.min.y, t, &dec, &dec_init);
        }
    } else {
        /* Tiled: the full-resolution level only (mip levels are not images). */
        uint32_t tw = 0, th = 0;
        exr_tile_level_mode_t lm;
        exr_tile_round_mode_t rm;
        if ((rv = exr_get_tile_descriptor(ctx, 0, &tw, &th, &lm, &rm)))
            return rv;
        if (tw < 1 || th < 1)
            return EXR_ERR_INVALID_ATTR;
        int64_t nx = ((int64_t)t->img->width + tw - 1) / tw;
        int64_t ny = ((int64_t)t->img->height + th - 1) / th;
        for (int64_t ty = 0; ty < ny && !rv; ty++)
            for (int64_t tx = 0; tx < nx && !rv; tx++) {
                if ((rv = exr_read_tile_chunk_info(ctx, 0, (int)tx, (int)ty, 0, 0, &ci)))
                    break;
                rv = exr_decode_chunk(ctx, &ci, (int)(tx * tw), (int)(ty * th), t, &dec, &dec_init);
            }
    }
    if (dec_init)
        exr_decoding_destroy(ctx, &dec);
    return rv;
}

/* Reads the header description into `out` (allocating its pixels). */
static hz_status exr_read_header(const char *path, exr_context_t ctx, exr_io *io, exr_image *out,
                                 exr_storage_t *storage, exr_attr_box2i_t *dw, hz_error *err)
{
    exr_result_t rv;
    int parts = 0;
    exr_attr_box2i_t disp;
    const exr_attr_chlist_t *chl = NULL;
    if ((rv = exr_get_count(ctx, &parts)) || (rv = exr_get_storage(ctx, 0, storage)) ||
        (rv = exr_get_data_window(ctx, 0, dw)) || (rv = exr_get_display_window(ctx, 0, &disp)) ||
        (rv = exr_get_channels(ctx, 0, &chl)))
        return exr_fail_code(err, path, "read the header of", rv, io);
    if (*storage != EXR_STORAGE_SCANLINE && *storage != EXR_STORAGE_TILED)
        return hz_fail(err, "%s: deep EXR images are not supported", path);
    int64_t w = (int64_t)dw->max.x - dw->min.x + 1, h = (int64_t)dw->max.y - dw->min.y + 1;
    int64_t dspw = (int64_t)disp.max.x - disp.min.x + 1, dsph = (int64_t)disp.max.y - disp.min.y + 1;
    if (w < 1 || h < 1 || w > INT32_MAX || h > INT32_MAX || dspw < 1 || dsph < 1 ||
        dspw > INT32_MAX || dsph > INT32_MAX)
        return hz_fail(err, "%s: invalid EXR data or display window", path);
    if (!chl || chl->num_channels < 1)
        return hz_fail(err, "%s: EXR image has no channels", path);
    /* Refuse before allocating: a corrupt header must not cause a huge
     * allocation. No EXR codec packs more than ~2000 float samples' bytes into
     * one stored byte (deflate tops out near 1032:1 on half data), so an image
     * claiming over 4096 times its file size (and over 64 MiB) has a corrupt
     * window (found by fuzzing: one flipped bit asked for 16 GiB). */
    double bytes = (double)w * (double)h * chl->num_channels * 4.0;
    struct stat fs;
    double file_bytes = stat(path, &fs) == 0 ? (double)fs.st_size : 0.0;
    if (bytes > 16.0 * 1024 * 1024 * 1024 ||
        (bytes > 64.0 * 1024 * 1024 && bytes > 4096.0 * file_bytes))
        return hz_fail(err,
                       "%s: EXR header claims %lldx%lld pixels with %d channels (%.0f MiB), more "
                       "than a %.0f-byte file can hold: corrupt data window?",
                       path, (long long)w, (long long)h, chl->num_channels,
                       bytes / (1024.0 * 1024.0), file_bytes);
    for (int c = 0; c < chl->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT)
            return hz_fail(err, "%s: EXR channel \"%s\" is not half or float (uint is not supported)",
                           path, e->name.str);
        if (e->x_sampling != 1 || e->y_sampling != 1)
            return hz_fail(err, "%s: EXR channel \"%s\" is subsampled, which is not supported", path,
                           e->name.str);
        if (e->name.length < 1 || e->name.length >= (int)sizeof out->channels[0].name)
            return hz_fail(err, "%s: EXR channel name \"%s\" is empty or too long", path, e->name.str);
    }
    if (exr_image_alloc(out, (int)w, (int)h, chl->num_channels, err) != HZ_OK)
        return HZ_ERROR;
    /* exr_image's display window starts at 0: express the data window relative to it. */
    out->display_width = (int)dspw;
    out->display_height = (int)dsph;
    out->data_x0 = (int)((int64_t)dw->min.x - disp.min.x);
    out->data_y0 = (int)((int64_t)dw->min.y - disp.min.y);
    out->file_display_x0 = disp.min.x;
    out->file_display_y0 = disp.min.y;
    for (int c = 0; c < chl->num_channels; c++) {
        memcpy(out->channels[c].name, chl->entries[c].name.str, (size_t)chl->entries[c].name.length);
        out->channels[c].half = chl->entries[c].pixel_type == EXR_PIXEL_HALF;
    }
    int32_t nattr = 0;
    if ((rv = exr_get_attribute_count(ctx, 0, &nattr)))
        return exr_fail_code(err, path, "read the header of", rv, io);
    for (int32_t a = 0; a < nattr; a++) {
        const exr_attribute_t *attr = NULL;
        if ((rv = exr_get_attribute_by_index(ctx, 0, EXR_ATTR_LIST_FILE_ORDER, a, &attr)))
            return exr_fail_code(err, path, "read the header of", rv, io);
        if (attr->type != EXR_ATTR_STRING || !attr->string || !attr->string->str)
            continue;
        /* "type" and "name" describe the part's structure, not the image. */
        if (strcmp(attr->name, "type") == 0 || strcmp(attr->name, "name") == 0)
            continue;
        /* Names and values that do not fit are skipped, not truncated. */
        if (strlen(attr->name) >= sizeof out->attribute_names[0] ||
            (size_t)attr->string->length >= sizeof out->attribute_values[0])
            continue;
        if (exr_image_add_attribute(out, attr->name, attr->string->str, err) != HZ_OK)
            return HZ_ERROR;
    }
    return HZ_OK;
}

hz_status exr_read(const char *path, exr_image *out, hz_error *err)
{
    memset(out, 0, sizeof *out);
    /* OpenEXR would wait for ever on a FIFO's open. */
    if (file_check_regular(path, err) != HZ_OK)
        return HZ_ERROR;
    exr_io io = {.fd = -1};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_error_handler;
    exr_context_t ctx = NULL;
    exr_io *outer = exr_io_enter(&io);
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        exr_io_leave(outer);
        return exr_fail_code(err, path, "read", rv, &io);
    }
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
    exr_attr_box2i_t dw;
    hz_status st = exr_read_header(path, ctx, &io, out, &storage, &dw, err);
    uint16_t **halfs = NULL;
    if (st == HZ_OK) {
        size_t npix = (size_t)out->width * (size_t)out->height;
        halfs = calloc((size_t)out->channel_count, sizeof *halfs);
        if (!halfs)
            st = hz_fail(err, "exr: out of memory");
        for (int c = 0; st == HZ_OK && c < out->channel_count; c++)
            if (out->channels[c].half && !(halfs[c] = calloc(npix, sizeof(uint16_t))))
                st = hz_fail(err, "exr: out of memory");
        if (st == HZ_OK) {
            exr_read_target t = {out, halfs};
            if ((rv = exr_read_pixels(ctx, storage, dw, &t)))
                st = exr_fail_code(err, path, "read pixels of", rv, &io);
        }
        for (int c = 0; st == HZ_OK && c < out->channel_count; c++)
            if (halfs[c])
                for (size_t i = 0; i < npix; i++)
                    out->channels[c].pixels[i] = exr_half_to_float(halfs[c][i]);
    }
    if (halfs)
        for (int c = 0; c < out->channel_count; c++)
            free(halfs[c]);
    free(halfs);
    exr_finish(&ctx);
    exr_io_leave(outer);
    if (st != HZ_OK)
        exr_image_free(out);
    return st;
}
