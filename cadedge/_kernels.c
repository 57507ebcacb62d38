/* cadedge's inner loops in C: exploration levels, node placement and de Boor evaluation (the functions
 * cadedge/_batch.c shares are declared in cadedge/_kernels.h; this module also registers _batch.c's).
 *
 * A refine runs these loops a few times per edge on short arrays, where numpy's per-call overhead
 * dominates. They are compiled once, when the package is installed, and load in a millisecond (a
 * JIT compiler cost seconds of import, cache loading and first-run compilation per process). The
 * module uses only the Python C API and the buffer protocol: no numpy headers, no OpenCASCADE, so it
 * builds against any numpy and OCP. Callers (cadedge/kernels.py) pass C-contiguous float64 / int64 /
 * bool arrays and preallocated outputs; every function checks the formats it is given.
 *
 * The arithmetic follows the former numba kernels operation by operation (compiled without FMA
 * contraction), so the grids are unchanged.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "_kernels.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

/* ---------------------------------------------------------------- buffers */

/* Get a C-contiguous buffer of the given element kind; 0 on success, -1 with an exception set. */
static int get(PyObject *obj, int kind, int writable, Py_buffer *view, const char *name)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0)
        return -1;
    const char *f = view->format ? view->format : "B";
    if (*f == '=' || *f == '<' || *f == '@')
        f++;
    int ok;
    switch (kind) {
    case F64: ok = (*f == 'd' && view->itemsize == 8); break;
    case I64: ok = ((*f == 'q' || *f == 'l') && view->itemsize == 8); break;
    default: ok = (*f == '?' && view->itemsize == 1); break;
    }
    if (!ok) {
        PyErr_Format(PyExc_TypeError, "%s: expected a contiguous %s array", name,
                     kind == F64 ? "float64" : kind == I64 ? "int64" : "bool");
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

void ck_release(Buffers *b)
{
    for (int i = 0; i < b->n; i++)
        PyBuffer_Release(&b->v[i]);
    b->n = 0;
}

/* The next argument as a buffer; returns its data or NULL (exception set). Once an argument has failed,
 * every later call returns NULL and keeps that first error, so a wrapper reads its arguments in a row and
 * checks only the last one. */
void *ck_arg(Buffers *b, PyObject *args, Py_ssize_t i, int kind, int writable, Py_ssize_t *count)
{
    if (PyErr_Occurred())
        return NULL;
    if (i >= PyTuple_GET_SIZE(args)) {
        PyErr_SetString(PyExc_TypeError, "too few arguments");
        return NULL;
    }
    char name[32];
    snprintf(name, sizeof name, "argument %d", (int)i + 1);
    if (get(PyTuple_GET_ITEM(args, i), kind, writable, &b->v[b->n], name) < 0)
        return NULL;
    Py_buffer *v = &b->v[b->n++];
    if (count)
        *count = v->len / v->itemsize;
    return v->buf;
}

int ck_num(PyObject *args, Py_ssize_t i, double *out)
{
    if (i >= PyTuple_GET_SIZE(args)) {
        PyErr_SetString(PyExc_TypeError, "too few arguments");
        return -1;
    }
    *out = PyFloat_AsDouble(PyTuple_GET_ITEM(args, i));
    return (*out == -1.0 && PyErr_Occurred()) ? -1 : 0;
}

/* ---------------------------------------------------------------- exploration */

Py_ssize_t ck_classify(Py_ssize_t n, const double *ua, const double *um, const double *ub, const double *pa,
                       const double *pm, const double *pb, const double *ratio, double tol, double *scale,
                       double min_width, double noise, double straight_share, double asymptotic, double *corners,
                       Py_ssize_t *n_corners_out, int64_t *split, double *gains, double *remainder_out)
{
    double *g = malloc(2 * (n > 0 ? n : 1) * sizeof(double));
    if (!g)
        return -1;
    double *two = g + n;
    for (Py_ssize_t i = 0; i < n; i++)
        g[i] = gain(pa, i, pm, i, pb, i, &two[i]);
    if (*scale < 0.0) {
        double s = 0.0;
        for (Py_ssize_t i = 0; i < n; i++)
            s += two[i];
        *scale = dmax(s, 0.0);
    }
    double remainder = 0.0;
    Py_ssize_t n_corners = 0, n_split = 0;
    for (Py_ssize_t i = 0; i < n; i++) {
        int straight = g[i] <= dmax(straight_share * dmax(two[i], *scale * 1e-3), noise);
        int resolved = g[i] / 3.0 <= tol * two[i] && ratio[i] <= asymptotic;
        int tiny = (ub[i] - ua[i]) <= min_width;
        if (straight)
            continue;
        if (resolved || tiny) {
            remainder += g[i] / 3.0;
            if (tiny && !resolved)
                corners[n_corners++] = um[i];
        } else {
            gains[n_split] = g[i];
            split[n_split++] = i;
        }
    }
    free(g);
    *n_corners_out = n_corners;
    *remainder_out = remainder;
    return n_split;
}

/* classify(ua, um, ub, pa, pm, pb, ratio, corners_out, split_out, gains_out,
 *          tol, scale, min_width, noise, straight, asymptotic) -> (remainder, n_corners, n_split, scale)
 * One level: which live triples are finished (their Richardson remainder summed), which are corners,
 * which split (indices and gains). scale < 0 sets it from this level's half chords. */
static PyObject *classify(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n, nc;
    double tol, scale, min_width, noise, straight_share, asymptotic;
    PyObject *result = NULL;
    const double *ua = ck_arg(&b, args, 0, F64, 0, &n);
    const double *um = ck_arg(&b, args, 1, F64, 0, NULL);
    const double *ub = ck_arg(&b, args, 2, F64, 0, NULL);
    const double *pa = ck_arg(&b, args, 3, F64, 0, NULL);
    const double *pm = ck_arg(&b, args, 4, F64, 0, NULL);
    const double *pb = ck_arg(&b, args, 5, F64, 0, NULL);
    const double *ratio = ck_arg(&b, args, 6, F64, 0, NULL);
    double *corners = ck_arg(&b, args, 7, F64, 1, &nc);
    int64_t *split = ck_arg(&b, args, 8, I64, 1, NULL);
    double *gains = ck_arg(&b, args, 9, F64, 1, NULL);
    if (!gains || ck_num(args, 10, &tol) || ck_num(args, 11, &scale) || ck_num(args, 12, &min_width) ||
        ck_num(args, 13, &noise) || ck_num(args, 14, &straight_share) || ck_num(args, 15, &asymptotic))
        goto done;
    double remainder;
    Py_ssize_t n_corners, n_split = ck_classify(n, ua, um, ub, pa, pm, pb, ratio, tol, &scale, min_width, noise,
                                                straight_share, asymptotic, corners, &n_corners, split, gains,
                                                &remainder);
    if (n_split < 0) {
        PyErr_NoMemory();
        goto done;
    }
    result = Py_BuildValue("dnnd", remainder, n_corners, n_split, scale);
done:
    ck_release(&b);
    return result;
}

/* The live triples of the next level: (a, q1, m) and (m, q3, b) of each of the n split triples (a, m, b), all
 * left halves first, each with (G_left + G_right) / G_parent. */
void ck_children(Py_ssize_t n, const double *ua, const double *um, const double *ub, const double *pa,
                 const double *pm, const double *pb, const int64_t *split, const double *gains, const double *q,
                 const double *pq, double *c_ua, double *c_um, double *c_ub, double *c_pa, double *c_pm,
                 double *c_pb, double *c_ratio)
{
    double unused;
    for (Py_ssize_t k = 0; k < n; k++) {
        Py_ssize_t i = split[k];
        double gl = gain(pa, i, pq, 2 * k, pm, i, &unused);
        double gr = gain(pm, i, pq, 2 * k + 1, pb, i, &unused);
        double r = gains[k] > 0 ? (gl + gr) / gains[k] : INFINITY;
        Py_ssize_t left = k, right = n + k;
        c_ua[left] = ua[i], c_um[left] = q[2 * k], c_ub[left] = um[i];
        c_ua[right] = um[i], c_um[right] = q[2 * k + 1], c_ub[right] = ub[i];
        for (int d = 0; d < 3; d++) {
            c_pa[3 * left + d] = pa[3 * i + d], c_pm[3 * left + d] = pq[3 * (2 * k) + d];
            c_pb[3 * left + d] = pm[3 * i + d];
            c_pa[3 * right + d] = pm[3 * i + d], c_pm[3 * right + d] = pq[3 * (2 * k + 1) + d];
            c_pb[3 * right + d] = pb[3 * i + d];
        }
        c_ratio[left] = c_ratio[right] = r;
    }
}

/* children(ua, um, ub, pa, pm, pb, split, gains, q, pq, c_ua, c_um, c_ub, c_pa, c_pm, c_pb, c_ratio)
 * The live triples of the next level: (a, q1, m) and (m, q3, b) of each split (a, m, b), all left
 * halves first, each with (G_left + G_right) / G_parent. */
static PyObject *children(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n;
    const double *ua = ck_arg(&b, args, 0, F64, 0, NULL);
    const double *um = ck_arg(&b, args, 1, F64, 0, NULL);
    const double *ub = ck_arg(&b, args, 2, F64, 0, NULL);
    const double *pa = ck_arg(&b, args, 3, F64, 0, NULL);
    const double *pm = ck_arg(&b, args, 4, F64, 0, NULL);
    const double *pb = ck_arg(&b, args, 5, F64, 0, NULL);
    const int64_t *split = ck_arg(&b, args, 6, I64, 0, &n);
    const double *gains = ck_arg(&b, args, 7, F64, 0, NULL);
    const double *q = ck_arg(&b, args, 8, F64, 0, NULL);
    const double *pq = ck_arg(&b, args, 9, F64, 0, NULL);
    double *c_ua = ck_arg(&b, args, 10, F64, 1, NULL);
    double *c_um = ck_arg(&b, args, 11, F64, 1, NULL);
    double *c_ub = ck_arg(&b, args, 12, F64, 1, NULL);
    double *c_pa = ck_arg(&b, args, 13, F64, 1, NULL);
    double *c_pm = ck_arg(&b, args, 14, F64, 1, NULL);
    double *c_pb = ck_arg(&b, args, 15, F64, 1, NULL);
    double *c_ratio = ck_arg(&b, args, 16, F64, 1, NULL);
    if (!c_ratio) {
        ck_release(&b);
        return NULL;
    }
    ck_children(n, ua, um, ub, pa, pm, pb, split, gains, q, pq, c_ua, c_um, c_ub, c_pa, c_pm, c_pb, c_ratio);
    ck_release(&b);
    Py_RETURN_NONE;
}

/* ---------------------------------------------------------------- placement */

static double chords(const double *p, const int64_t *nodes, Py_ssize_t count)
{
    double s = 0.0;
    for (Py_ssize_t k = 0; k + 1 < count; k++)
        s += distance(p, nodes[k], p, nodes[k + 1]);
    return s;
}

/* Greedy farthest-reach nodes into out; returns their count. Each chord misses at most cap of the
 * samples' length, is at most max_length long and, where the curve allows, at least min_length;
 * stops (sorted, ending with the last sample) are always nodes. */
static Py_ssize_t cover(const double *p, Py_ssize_t n, const double *cum, double cap, double min_length,
                        double max_length, const int64_t *stops, int64_t *out)
{
    Py_ssize_t last = n - 1, count = 1, i = 0, s = 0;
    out[0] = 0;
    while (i < last) {
        while (stops[s] <= i)
            s++;
        Py_ssize_t stop = stops[s], reach = stop, j = i + 1;
#ifdef __SSE2__
        /* two chords at a time (the same correctly rounded values as distance()), tested in order */
        const double *a = p + 3 * i;
        __m128d ax = _mm_set1_pd(a[0]), ay = _mm_set1_pd(a[1]), az = _mm_set1_pd(a[2]);
        for (; j + 1 <= stop; j += 2) {
            const double *q = p + 3 * j;
            __m128d dx = _mm_sub_pd(_mm_set_pd(q[3], q[0]), ax), dy = _mm_sub_pd(_mm_set_pd(q[4], q[1]), ay);
            __m128d dz = _mm_sub_pd(_mm_set_pd(q[5], q[2]), az);
            double chord[2];
            _mm_storeu_pd(chord, _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)),
                                                        _mm_mul_pd(dz, dz))));
            if ((cum[j] - cum[i]) - chord[0] > cap || chord[0] > max_length) {
                reach = j - 1;
                goto reached;
            }
            if ((cum[j + 1] - cum[i]) - chord[1] > cap || chord[1] > max_length) {
                reach = j;
                goto reached;
            }
        }
#endif
        for (; j <= stop; j++) {
            double chord = distance(p, i, p, j);
            if ((cum[j] - cum[i]) - chord > cap || chord > max_length) {
                reach = j - 1;
                break;
            }
        }
#ifdef __SSE2__
    reached:
#endif
        if (reach < i + 1)
            reach = i + 1;
        if (min_length > 0.0 && reach < stop && distance(p, i, p, reach) < min_length) {
            Py_ssize_t far = stop;
            for (Py_ssize_t j = reach + 1; j <= stop; j++) {
                if (distance(p, i, p, j) >= min_length) {
                    far = j;
                    break;
                }
            }
            reach = far;
        }
        out[count++] = reach;
        i = reach;
    }
    if (min_length > 0.0 && count > 2 && distance(p, out[count - 2], p, out[count - 1]) < min_length) {
        out[count - 2] = out[count - 1];
        count--;
    }
    return count;
}

/* two[c] = |p[c] - p[lo]| + |p[hi] - p[c]| for lo < c < hi (as distance(), two samples at a time where SSE2
 * is there: the same correctly rounded square roots of the same sums); returns their largest (-1 if none). */
static double chord_pairs(const double *p, int64_t lo, int64_t hi, double *two)
{
    int64_t c = lo + 1;
    double most = -1.0;
#ifdef __SSE2__
    __m128d top = _mm_set1_pd(-1.0);
    const double *a = p + 3 * lo, *b = p + 3 * hi;
    __m128d ax = _mm_set1_pd(a[0]), ay = _mm_set1_pd(a[1]), az = _mm_set1_pd(a[2]);
    __m128d bx = _mm_set1_pd(b[0]), by = _mm_set1_pd(b[1]), bz = _mm_set1_pd(b[2]);
    for (; c + 1 < hi; c += 2) {
        const double *q = p + 3 * c;
        __m128d qx = _mm_set_pd(q[3], q[0]), qy = _mm_set_pd(q[4], q[1]), qz = _mm_set_pd(q[5], q[2]);
        __m128d dx = _mm_sub_pd(qx, ax), dy = _mm_sub_pd(qy, ay), dz = _mm_sub_pd(qz, az);
        __m128d ex = _mm_sub_pd(bx, qx), ey = _mm_sub_pd(by, qy), ez = _mm_sub_pd(bz, qz);
        __m128d d1 = _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz)));
        __m128d d2 = _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(ex, ex), _mm_mul_pd(ey, ey)), _mm_mul_pd(ez, ez)));
        __m128d sum = _mm_add_pd(d1, d2);
        _mm_storeu_pd(two + c, sum);
        top = _mm_max_pd(top, sum);
    }
    double lanes[2];
    _mm_storeu_pd(lanes, top);
    most = dmax(lanes[0], lanes[1]);
#endif
    for (; c < hi; c++) {
        two[c] = distance(p, lo, p, c) + distance(p, c, p, hi);
        most = dmax(most, two[c]);
    }
    return most;
}

/* Move interior nodes (not on fixed samples) to the sample between their neighbours that maximises
 * the two chords; odd positions then even ones, until nothing moves or sweeps runs out. */
static void polish(const double *p, int64_t *nodes, Py_ssize_t count, int sweeps, const uint8_t *fixed,
                   uint8_t *dirty, double *two)
{
    /* A node is scanned again only after a neighbour moved: between the same neighbours the scan finds the
     * same best sample, which the node already holds or did not beat, so skipping it changes nothing. */
    memset(dirty, 1, count);
    for (int sweep = 0; sweep < sweeps; sweep++) {
        int moved = 0;
        for (int parity = 1; parity >= 0; parity--) {
            for (Py_ssize_t k = 1; k < count - 1; k++) {
                if (k % 2 != parity || fixed[nodes[k]] || !dirty[k])
                    continue;
                dirty[k] = 0;
                int64_t lo = nodes[k - 1], hi = nodes[k + 1];
                double best = chord_pairs(p, lo, hi, two);
                int64_t at = -1;
                for (int64_t c = lo + 1; c < hi; c++) /* the first sample that reaches the largest */
                    if (two[c] == best) {
                        at = c;
                        break;
                    }
                if (at < 0)
                    continue;
                double current = two[nodes[k]]; /* (the node lies between its neighbours) */
                if (best > current * (1.0 + 1e-15)) {
                    nodes[k] = at;
                    moved = 1;
                    dirty[k - 1] = dirty[k + 1] = 1;
                }
            }
        }
        if (!moved)
            break;
    }
}

enum { MEMO = 8 };

typedef struct {
    const double *p, *cum;
    Py_ssize_t n;
    double min_length, max_length;
    const int64_t *stops;
    const uint8_t *fixed;
    int64_t *buf;
    uint8_t *dirty;
    double *two; /* polish's scratch, n doubles */
    /* The last MEMO plans: each one's cover (raw, raw_count) and what polishing it gave (polished, miss).
     * The caps of a bisection often give a cover met before, whose polished grid is then copied instead of
     * made again (the same nodes: polishing depends on the cover alone). */
    int64_t *raw[MEMO], *polished[MEMO];
    Py_ssize_t raw_count[MEMO];
    double miss[MEMO];
    int next;
} Cover;

/* Greedy cover under cap, polished, into nodes: returns the count; *miss gets the deficit. */
static Py_ssize_t plan(Cover *c, double cap, int64_t *nodes, double *miss)
{
    Py_ssize_t count = cover(c->p, c->n, c->cum, cap, c->min_length, c->max_length, c->stops, c->buf);
    for (int k = 0; k < MEMO; k++) {
        if (count == c->raw_count[k] && !memcmp(c->buf, c->raw[k], count * sizeof(int64_t))) {
            memcpy(nodes, c->polished[k], count * sizeof(int64_t));
            *miss = c->miss[k];
            return count;
        }
    }
    memcpy(nodes, c->buf, count * sizeof(int64_t));
    if (count > 2)
        polish(c->p, nodes, count, 4, c->fixed, c->dirty, c->two);
    *miss = c->cum[c->n - 1] - chords(c->p, nodes, count);
    int k = c->next;
    c->next = (k + 1) % MEMO;
    memcpy(c->raw[k], c->buf, count * sizeof(int64_t));
    memcpy(c->polished[k], nodes, count * sizeof(int64_t));
    c->raw_count[k] = count, c->miss[k] = *miss;
    return count;
}

/* The fewest node indices (greedy + bisection on the cap, polished) whose chords miss at most budget
 * of the samples' length, written to out (n entries); returns their count, -1 if out of memory. With drop,
 * the polished grid is then tried with one node fewer, as long as that meets the budget. */
Py_ssize_t ck_fewest(const double *p, const double *cum, Py_ssize_t n, const int64_t *stops, const uint8_t *fixed,
                     int64_t *out, double budget, double min_length, double max_length, int drop)
{
    int64_t *work = malloc((3 + 2 * MEMO) * n * sizeof(int64_t));
    uint8_t *dirty = malloc(n);
    double *two = malloc(n * sizeof(double));
    if (!work || !dirty || !two) {
        free(work), free(dirty), free(two);
        return -1;
    }
    int64_t *buf = work, *tmp = work + n, *best = out;
    Cover c = {p, cum, n, min_length, max_length, stops, fixed, buf, dirty, two};
    for (int k = 0; k < MEMO; k++)
        c.raw[k] = work + (3 + 2 * k) * n, c.polished[k] = work + (4 + 2 * k) * n, c.raw_count[k] = -1;
    double total = cum[n - 1], miss;
    Py_ssize_t best_count = plan(&c, dmax(budget, 0.0), best, &miss);
    if (miss > budget) { /* the per-segment cap equal to the whole budget is too loose: bisect it down */
        double lo = 0.0, hi = dmax(budget, 0.0);
        int found = 0;
        for (int it = 0; it < 60; it++) {
            double mid = 0.5 * (lo + hi);
            Py_ssize_t cnt = plan(&c, mid, tmp, &miss);
            if (miss <= budget) {
                memcpy(best, tmp, cnt * sizeof(int64_t));
                best_count = cnt, found = 1, lo = mid;
            } else {
                hi = mid;
            }
            if (hi - lo <= 1e-3 * hi)
                break;
        }
        if (!found)
            best_count = plan(&c, 0.0, best, &miss);
    }
    /* The polished grid may leave room for fewer nodes: bisect for a cap that drops one, polish, check. */
    int64_t *fewer = work + 2 * n;
    while (drop && best_count > 2) {
        Py_ssize_t count = best_count, fewer_count = 0;
        double lo = 0.0, hi = total;
        int found = 0;
        for (int it = 0; it < 40; it++) {
            double mid = 0.5 * (lo + hi);
            Py_ssize_t cnt = cover(p, n, cum, mid, min_length, max_length, stops, buf);
            if (cnt < count) {
                memcpy(fewer, buf, cnt * sizeof(int64_t));
                fewer_count = cnt, found = 1, hi = mid;
            } else {
                lo = mid;
            }
            if (hi - lo <= 1e-4 * hi)
                break;
        }
        if (!found)
            break;
        if (fewer_count > 2)
            polish(p, fewer, fewer_count, 8, fixed, dirty, two);
        if (total - chords(p, fewer, fewer_count) > budget)
            break;
        memcpy(best, fewer, fewer_count * sizeof(int64_t));
        best_count = fewer_count;
    }
    free(work), free(dirty), free(two);
    return best_count;
}

/* fewest(points, cum, stops, fixed, out, budget, min_length, max_length, drop) -> count (see ck_fewest) */
static PyObject *fewest(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n;
    double budget, min_length, max_length;
    PyObject *result = NULL;
    const double *p = ck_arg(&b, args, 0, F64, 0, NULL);
    const double *cum = ck_arg(&b, args, 1, F64, 0, &n);
    const int64_t *stops = ck_arg(&b, args, 2, I64, 0, NULL);
    const uint8_t *fixed = ck_arg(&b, args, 3, BOOL, 0, NULL);
    int64_t *out = ck_arg(&b, args, 4, I64, 1, NULL);
    if (!out || ck_num(args, 5, &budget) || ck_num(args, 6, &min_length) || ck_num(args, 7, &max_length))
        goto done;
    if (PyTuple_GET_SIZE(args) < 9) {
        PyErr_SetString(PyExc_TypeError, "too few arguments");
        goto done;
    }
    int drop = PyObject_IsTrue(PyTuple_GET_ITEM(args, 8));
    if (drop < 0)
        goto done;
    if (n < 1) {
        PyErr_SetString(PyExc_ValueError, "fewest: no samples");
        goto done;
    }
    Py_ssize_t count = ck_fewest(p, cum, n, stops, fixed, out, budget, min_length, max_length, drop);
    result = count < 0 ? PyErr_NoMemory() : PyLong_FromSsize_t(count);
done:
    ck_release(&b);
    return result;
}

/* Cumulative measure M such that a chord spanning dM misses about dM**3 (see
 * cadedge.placement.deficit_measure); 0 on success, -1 if out of memory. */
int ck_deficit_measure(const double *p, const double *cum, Py_ssize_t n, const int64_t *corners, Py_ssize_t nc,
                       double *measure)
{
    double *rho = calloc(n > 0 ? n : 1, sizeof(double));
    if (!rho)
        return -1;
    for (Py_ssize_t i = 1; i < n - 1; i++) {
        double h1 = cum[i] - cum[i - 1], h2 = cum[i + 1] - cum[i];
        double denom = 3.0 * h1 * h2 * (h1 + h2);
        if (denom > 0)
            rho[i] = cbrt(dmax(h1 + h2 - distance(p, i - 1, p, i + 1), 0.0) / denom);
    }
    if (n >= 3)
        rho[0] = rho[1], rho[n - 1] = rho[n - 2];
    for (Py_ssize_t k = 0; k < nc; k++)
        rho[corners[k]] = 0.0;
    if (n > 0)
        measure[0] = 0.0;
    for (Py_ssize_t i = 0; i + 1 < n; i++)
        measure[i + 1] = measure[i] + 0.5 * (rho[i] + rho[i + 1]) * (cum[i + 1] - cum[i]);
    free(rho);
    return 0;
}

/* deficit_measure(points, cum, corners, out) (see ck_deficit_measure) */
static PyObject *deficit_measure(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n, nc;
    const double *p = ck_arg(&b, args, 0, F64, 0, NULL);
    const double *cum = ck_arg(&b, args, 1, F64, 0, &n);
    const int64_t *corners = ck_arg(&b, args, 2, I64, 0, &nc);
    double *measure = ck_arg(&b, args, 3, F64, 1, NULL);
    if (!measure) {
        ck_release(&b);
        return NULL;
    }
    int status = ck_deficit_measure(p, cum, n, corners, nc, measure);
    ck_release(&b);
    if (status < 0)
        return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* np.interp(x, xp, fp) for increasing x and non-decreasing xp, by one forward sweep. */
void ck_interp(const double *x, Py_ssize_t nx, const double *xp, const double *fp, Py_ssize_t np_,
                   double *out)
{
    Py_ssize_t last = np_ - 1, j = 0;
    for (Py_ssize_t k = 0; k < nx; k++) {
        double v = x[k];
        if (v >= xp[last]) {
            out[k] = fp[last];
            continue;
        }
        if (v < xp[0]) {
            out[k] = fp[0];
            continue;
        }
        while (xp[j + 1] <= v)
            j++;
        out[k] = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) * (v - xp[j]) + fp[j];
    }
}

/* interp_sorted(x, xp, fp, out) */
static PyObject *interp_sorted(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t nx, nxp, nfp, nout;
    const double *x = ck_arg(&b, args, 0, F64, 0, &nx);
    const double *xp = ck_arg(&b, args, 1, F64, 0, &nxp);
    const double *fp = ck_arg(&b, args, 2, F64, 0, &nfp);
    double *out = ck_arg(&b, args, 3, F64, 1, &nout);
    if (!out) {
        ck_release(&b);
        return NULL;
    }
    if (nxp < 1 || nfp != nxp || nout != nx) {
        ck_release(&b);
        PyErr_SetString(PyExc_ValueError, "interp_sorted: mismatched lengths");
        return NULL;
    }
    ck_interp(x, nx, xp, fp, nxp, out);
    ck_release(&b);
    Py_RETURN_NONE;
}

/* Parameters at equal steps of measure within each piece between cut samples (alloc segments each),
 * interpolated in arc length then in parameter; strictly increasing. out holds size >= 1 + sum(max(alloc,
 * 1)) entries. Returns the count, -1 if out of memory. */
Py_ssize_t ck_place(const double *params, const double *cum, const double *measure, const int64_t *cut,
                    const int64_t *alloc, Py_ssize_t pieces, double *out, Py_ssize_t size)
{
    int64_t most = 1;
    for (Py_ssize_t piece = 0; piece < pieces; piece++)
        if (alloc[piece] > most)
            most = alloc[piece];
    double *s = malloc(2 * most * sizeof(double));
    if (!s)
        return -1;
    double *t = s + most;
    Py_ssize_t w = 1;
    out[0] = params[0];
    for (Py_ssize_t piece = 0; piece < pieces; piece++) {
        int64_t i0 = cut[piece], i1 = cut[piece + 1], k = alloc[piece];
        if (k > 1) {
            int by_measure = measure[i1] > measure[i0];
            for (int64_t j = 1; j < k; j++)
                s[j - 1] = by_measure ? measure[i0] + (measure[i1] - measure[i0]) * (double)j / (double)k
                                      : cum[i0] + (cum[i1] - cum[i0]) * (double)j / (double)k;
            const double *x = s;
            if (by_measure) {
                ck_interp(s, k - 1, measure + i0, cum + i0, i1 - i0 + 1, t);
                x = t;
            }
            ck_interp(x, k - 1, cum + i0, params + i0, i1 - i0 + 1, s == x ? t : s);
            const double *u = s == x ? t : s;
            for (int64_t j = 0; j < k - 1; j++) {
                if (u[j] > out[w - 1] && w < size)
                    out[w++] = u[j];
            }
        }
        if (params[i1] > out[w - 1] && w < size)
            out[w++] = params[i1];
    }
    free(s);
    return w;
}

/* place(params, cum, measure, cut, alloc, out) -> count (see ck_place) */
static PyObject *place(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t pieces, size;
    PyObject *result = NULL;
    const double *params = ck_arg(&b, args, 0, F64, 0, NULL);
    const double *cum = ck_arg(&b, args, 1, F64, 0, NULL);
    const double *measure = ck_arg(&b, args, 2, F64, 0, NULL);
    const int64_t *cut = ck_arg(&b, args, 3, I64, 0, NULL);
    const int64_t *alloc = ck_arg(&b, args, 4, I64, 0, &pieces);
    double *out = ck_arg(&b, args, 5, F64, 1, &size);
    if (out) {
        Py_ssize_t count = ck_place(params, cum, measure, cut, alloc, pieces, out, size);
        result = count < 0 ? PyErr_NoMemory() : PyLong_FromSsize_t(count);
    }
    ck_release(&b);
    return result;
}

/* ---------------------------------------------------------------- splines */

/* de Boor's algorithm for one point x on the span's degree + 1 coefficients, copied into d (degree + 1, dim),
 * writing the point to out. Inlined with dim a constant (3, or 4 for rational curves), the loops unroll. */
static inline void de_boor_point(const double *knots, const double *coef, Py_ssize_t span, long degree,
                                 Py_ssize_t dim, double x, double *d, double *out)
{
    for (long j = 0; j <= degree; j++)
        for (Py_ssize_t c = 0; c < dim; c++)
            d[j * dim + c] = coef[(j + span - degree) * dim + c];
    for (long r = 1; r <= degree; r++) {
        for (long j = degree; j >= r; j--) {
            double k0 = knots[j + span - degree];
            double width = knots[j + 1 + span - r] - k0;
            double alpha = width > 0 ? (x - k0) / width : 0.0;
            for (Py_ssize_t c = 0; c < dim; c++)
                d[j * dim + c] = (1.0 - alpha) * d[(j - 1) * dim + c] + alpha * d[j * dim + c];
        }
    }
    for (Py_ssize_t c = 0; c < dim; c++)
        out[c] = d[degree * dim + c];
}

/* Points of the spline (knots (nk), coef (n, dim), degree) at u (nu) into out (nu, dim); outside the knots
 * the end pieces are extended. 0 on success, -1 if out of memory. */
int ck_de_boor(const double *knots, Py_ssize_t nk, const double *coef, Py_ssize_t n, Py_ssize_t dim,
               const double *u, Py_ssize_t nu, double *out, long degree)
{
    double *d = malloc((degree + 1) * dim * sizeof(double));
    if (!d) {
        return -1;
    }
    for (Py_ssize_t m = 0; m < nu; m++) {
        double x = u[m];
        Py_ssize_t span = knot_span(knots, nk, n, degree, x);
        if (dim == 3)
            de_boor_point(knots, coef, span, degree, 3, x, d, out + m * 3);
        else if (dim == 4)
            de_boor_point(knots, coef, span, degree, 4, x, d, out + m * 4);
        else
            de_boor_point(knots, coef, span, degree, dim, x, d, out + m * dim);
    }
    free(d);
    return 0;
}

/* de_boor(knots, coef, u, out, degree): points of the spline (knots, coef (n, dim), degree) at u into
 * out (len(u), dim); outside the knots the end pieces are extended. */
static PyObject *de_boor(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t nk, ncoef, nu, nout;
    PyObject *result = NULL;
    const double *knots = ck_arg(&b, args, 0, F64, 0, &nk);
    const double *coef = ck_arg(&b, args, 1, F64, 0, &ncoef);
    const double *u = ck_arg(&b, args, 2, F64, 0, &nu);
    double *out = ck_arg(&b, args, 3, F64, 1, &nout);
    if (!out)
        goto done;
    long degree = PyTuple_GET_SIZE(args) > 4 ? PyLong_AsLong(PyTuple_GET_ITEM(args, 4)) : -1;
    if (degree == -1 && PyErr_Occurred())
        goto done;
    Py_ssize_t dim = b.v[1].ndim == 2 ? b.v[1].shape[1] : 0;
    Py_ssize_t n = dim ? ncoef / dim : 0;
    if (degree < 0 || dim < 1 || n < degree + 1 || nk != n + degree + 1 || nout != nu * dim) {
        PyErr_SetString(PyExc_ValueError, "de_boor: inconsistent knots, coefficients or output");
        goto done;
    }
    if (ck_de_boor(knots, nk, coef, n, dim, u, nu, out, degree) < 0) {
        PyErr_NoMemory();
        goto done;
    }
    Py_INCREF(Py_None);
    result = Py_None;
done:
    ck_release(&b);
    return result;
}

/* ---------------------------------------------------------------- module */

static PyMethodDef methods[] = {
    {"classify", classify, METH_VARARGS, "One exploration level: finished, corner and split triples."},
    {"children", children, METH_VARARGS, "The next exploration level's live triples."},
    {"fewest", fewest, METH_VARARGS, "The fewest node indices for a deficit budget (greedy cover + polish)."},
    {"deficit_measure", deficit_measure, METH_VARARGS, "Cumulative deficit measure along samples."},
    {"interp_sorted", interp_sorted, METH_VARARGS, "np.interp for sorted x, by one forward sweep."},
    {"place", place, METH_VARARGS, "Parameters at equal steps of a measure, piece by piece."},
    {"de_boor", de_boor, METH_VARARGS, "Spline points by de Boor's algorithm."},
    {"evaluate_edges", ck_evaluate_edges, METH_VARARGS, "Points of many edges' curves from a geometry table."},
    {"edge_lengths", ck_edge_lengths, METH_VARARGS, "Lengths of many edges from a geometry table (Gauss-Legendre)."},
    {"refine_edges", ck_refine_edges, METH_VARARGS, "Target-mode grids of many edges in one call."},
    {"parse_curves", ck_parse_curves, METH_VARARGS, "Curves written by OCCT's BinTools_CurveSet as geometry table rows."},
    {"parse_shapes", ck_parse_shapes, METH_VARARGS, "A shape written by OCCT's BinTools_ShapeSet: topology and edges."},
    {"min_angles", ck_min_angles, METH_VARARGS, "The smallest angle of each triangle, in degrees."},
    {"climb_trials", ck_climb_trials, METH_VARARGS, "The local search's trial positions, the best per node."},
    {"tri_normals", ck_tri_normals, METH_VARARGS, "Each triangle's normal, twice its area in length."},
    {"idw_size", ck_idw_size, METH_VARARGS, "Inverse-distance mean of the nearest samples' sizes at a point."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernels",
                                    "cadedge's compiled inner loops (see cadedge/kernels.py).", -1, methods};

PyMODINIT_FUNC PyInit__kernels(void) { return PyModule_Create(&module); }
