/* Readers of OCCT's binary streams (BinTools), shared by cadedge/_bintools.c (curves, surfaces, the
 * section headers) and cadedge/_shapedump.c (a whole shape). Every read is bounds-checked: a stream that
 * ends early or does not match the layout sets Reader.error instead of reading past its end. */
#ifndef CADEDGE_BINTOOLS_H
#define CADEDGE_BINTOOLS_H

#include <stdlib.h>
#include <string.h>

#include "_kernels.h"

#define MAX_DEPTH 64 /* nesting of trimmed/offset curves and surfaces */

typedef struct {
    const unsigned char *d;
    Py_ssize_t size, pos;
    const char *error; /* the first reason the stream was refused */
} Reader;

typedef struct {
    double *d;
    Py_ssize_t n, cap;
} Vec;

/* A growable array of doubles: room for ``extra`` more, or ``k`` values appended (-1 when out of memory). */
int vec_reserve(Vec *v, Py_ssize_t extra);
int vec_push(Vec *v, const double *x, Py_ssize_t k);

static inline PyObject *as_bytes(const void *data, Py_ssize_t size)
{
    return PyByteArray_FromStringAndSize(data, size);
}

/* Little-endian reads (BinTools fixes that byte order on every machine); 0 after a failed need(). */
static inline int need(Reader *r, Py_ssize_t k)
{
    if (k < 0 || r->pos + k > r->size) {
        if (!r->error)
            r->error = "the stream ends inside an item";
        return 0;
    }
    return 1;
}

static inline uint64_t le(const unsigned char *p, int size)
{
    uint64_t v = 0;
    for (int k = size - 1; k >= 0; k--)
        v = (v << 8) | p[k];
    return v;
}

static inline double le_double(const unsigned char *p)
{
    uint64_t bits = le(p, 8);
    double x;
    memcpy(&x, &bits, 8);
    return x;
}

static inline int u8(Reader *r) { return need(r, 1) ? r->d[r->pos++] : -1; }
static inline long u16(Reader *r) { return need(r, 2) ? (long)le(r->d + (r->pos += 2) - 2, 2) : -1; }
static inline long i32(Reader *r) { return need(r, 4) ? (long)(int32_t)le(r->d + (r->pos += 4) - 4, 4) : 0; }
static inline double f64(Reader *r) { return need(r, 8) ? le_double(r->d + (r->pos += 8) - 8) : 0.0; }
static inline int skip(Reader *r, Py_ssize_t k) { return need(r, k) ? (r->pos += k, 1) : 0; }

static inline int fail(Reader *r, const char *why)
{
    if (!r->error)
        r->error = why;
    return 0;
}

/* A section header "<name> <count>\n": the count, or -1. */
Py_ssize_t bt_header(Reader *r, const char *name);
int bt_skip_curve2d(Reader *r, int depth);
int bt_skip_curve3d(Reader *r, int depth);
int bt_skip_surface(Reader *r, int depth);
/* count curves from r->pos as geometry table rows into meta (count x 6), offsets (count + 1), out;
 * 1, 0 (refused: r->error says why) or -1 (out of memory). */
int bt_parse_curves_at(Reader *r, Py_ssize_t count, int64_t *meta, int64_t *offsets, Vec *out);
/* NULL with a ValueError naming where and why the stream was refused. */
PyObject *bt_refused(Reader *r, const char *where);

#endif
