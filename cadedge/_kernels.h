/* cadedge's compiled inner loops shared between cadedge/_kernels.c (the loops and their Python wrappers)
 * and cadedge/_batch.c (the whole target-mode refinement of many edges in one call). */
#ifndef CADEDGE_KERNELS_H
#define CADEDGE_KERNELS_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

enum { F64 = 'd', I64 = 'q', BOOL = '?' };

/* Buffers taken from a call's arguments, released together. */
#define MAXBUF 24
typedef struct {
    Py_buffer v[MAXBUF];
    int n;
} Buffers;

void ck_release(Buffers *b);
/* Argument i as a C-contiguous buffer of kind (F64, I64, BOOL); its data, or NULL with an exception set
 * (also when an exception is already set: an earlier argument failed, so only the last result needs a check). */
void *ck_arg(Buffers *b, PyObject *args, Py_ssize_t i, int kind, int writable, Py_ssize_t *count);
/* Argument i as a float; 0, or -1 with an exception set. */
int ck_num(PyObject *args, Py_ssize_t i, double *out);

static inline double distance(const double *p, Py_ssize_t i, const double *q, Py_ssize_t j)
{
    double dx = q[3 * j] - p[3 * i];
    double dy = q[3 * j + 1] - p[3 * i + 1];
    double dz = q[3 * j + 2] - p[3 * i + 2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static inline double dmax(double a, double b) { return b > a ? b : a; }

/* Gain of the triple pa[i], pm[j], pb[k]; *two gets the two half chords. */
static inline double gain(const double *pa, Py_ssize_t i, const double *pm, Py_ssize_t j, const double *pb,
                          Py_ssize_t k, double *two)
{
    double t = distance(pa, i, pm, j) + distance(pm, j, pb, k);
    *two = t;
    return dmax(t - distance(pa, i, pb, k), 0.0);
}

/* The B-spline knot span of x: the last knot <= x (numpy's searchsorted, side="right", less one), clamped to
 * [degree, n - 1] so the ends evaluate on the first and last spans. */
static inline Py_ssize_t knot_span(const double *knots, Py_ssize_t nk, Py_ssize_t n, long degree, double x)
{
    Py_ssize_t lo = 0, hi = nk; /* first knot > x */
    while (lo < hi) {
        Py_ssize_t mid = (lo + hi) / 2;
        if (knots[mid] <= x)
            lo = mid + 1;
        else
            hi = mid;
    }
    Py_ssize_t span = lo - 1;
    if (span < degree)
        span = degree;
    if (span > n - 1)
        span = n - 1;
    return span;
}

/* One exploration level over n live triples; returns the number split (-1: out of memory). */
Py_ssize_t ck_classify(Py_ssize_t n, const double *ua, const double *um, const double *ub, const double *pa,
                       const double *pm, const double *pb, const double *ratio, double tol, double *scale,
                       double min_width, double noise, double straight_share, double asymptotic, double *corners,
                       Py_ssize_t *n_corners_out, int64_t *split, double *gains, double *remainder_out);
void ck_children(Py_ssize_t n, const double *ua, const double *um, const double *ub, const double *pa,
                 const double *pm, const double *pb, const int64_t *split, const double *gains, const double *q,
                 const double *pq, double *c_ua, double *c_um, double *c_ub, double *c_pa, double *c_pm,
                 double *c_pb, double *c_ratio);
Py_ssize_t ck_fewest(const double *p, const double *cum, Py_ssize_t n, const int64_t *stops, const uint8_t *fixed,
                     int64_t *out, double budget, double min_length, double max_length, int drop);
int ck_deficit_measure(const double *p, const double *cum, Py_ssize_t n, const int64_t *corners, Py_ssize_t nc,
                       double *measure);
void ck_interp(const double *x, Py_ssize_t nx, const double *xp, const double *fp, Py_ssize_t np_, double *out);
Py_ssize_t ck_place(const double *params, const double *cum, const double *measure, const int64_t *cut,
                    const int64_t *alloc, Py_ssize_t pieces, double *out, Py_ssize_t size);
int ck_de_boor(const double *knots, Py_ssize_t nk, const double *coef, Py_ssize_t n, Py_ssize_t dim,
               const double *u, Py_ssize_t nu, double *out, long degree);

/* cadedge/_batch.c's, cadedge/_lengths.c's, cadedge/_shapedump.c's, cadedge/_angles.c's and cadedge/_idw.c's functions, registered by cadedge/_kernels.c's
 * module. */
PyObject *ck_evaluate_edges(PyObject *self, PyObject *args);
PyObject *ck_refine_edges(PyObject *self, PyObject *args);
PyObject *ck_parse_curves(PyObject *self, PyObject *args);
PyObject *ck_parse_shapes(PyObject *self, PyObject *args);
PyObject *ck_edge_lengths(PyObject *self, PyObject *args);
PyObject *ck_min_angles(PyObject *self, PyObject *args);
PyObject *ck_climb_trials(PyObject *self, PyObject *args);
PyObject *ck_tri_normals(PyObject *self, PyObject *args);
PyObject *ck_idw_size(PyObject *self, PyObject *args);

#endif
