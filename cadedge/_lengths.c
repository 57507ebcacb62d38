/* Lengths of edges from the geometry table (cadedge/_batch.c's layout), by adaptive Gauss-Kronrod quadrature
 * of |C'(u)| in C, instead of one OCCT GCPnts_AbscissaPoint::Length call (and an adaptor) per edge.
 *
 * The integral is split at every knot inside the range (a spline is smooth between knots; a periodic spline's
 * knots over all periods are the row's hints), and a conic's range into pieces of at most a quarter turn. Each
 * piece is integrated by the 15-point Kronrod rule, whose difference from the embedded 7-point Gauss rule bounds
 * its error; where that bound exceeds both the piece's share (by parameter width) of TOL_REL of the edge's
 * length (from the first pass) and TOL_REL of its own length, its halves are integrated in turn, to MAX_DEPTH
 * levels and MAX_RULES rules. A
 * piece that does not settle, a non-finite value or a curve this file does not integrate gives NaN: the caller
 * then takes OCCT's length. The derivatives: a spline's from the de Boor triangle's last two points
 * (C' = p (d1 - d0) / (t[span + 1] - t[span])), a rational spline's by the quotient rule on its homogeneous
 * coordinates; a conic's and a hyperbola's in closed form.
 */
#include <stdlib.h>
#include <string.h>

#include "_kernels.h"

enum { LINE = 0, CONIC = 1, SPLINE = 2, HYPERBOLA = 3 };
/* The bound on the 15-point rule's error that is accepted, relative to the edge's length (shared by the pieces)
 * or to the piece's own: the bound (the 7-point rule's error) exceeds the 15-point rule's by orders of
 * magnitude, so the lengths agree with OCCT's to about 1e-16 on the corpus; a tighter bound only subdivides
 * short spans whose derivatives (differences of nearby points) carry rounding noise. */
#define TOL_REL 1e-10
#define MAX_DEPTH 30
#define MAX_RULES 1024 /* Gauss-Kronrod rules per edge before giving up */
#define MAX_SPLIT 1.5707963267948966 /* a conic's pieces: at most a quarter turn */

/* The 15-point Kronrod rule and its embedded 7-point Gauss rule on [-1, 1] (QUADPACK's qk15): nodes
 * XK[0..7] (XK[7] = 0), the Kronrod weights WK, the Gauss weights WG of XK[1], XK[3], XK[5], XK[7]. */
static const double XK[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                             0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                             0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                             0.207784955007898467600689403773245, 0.0};
static const double WK[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                             0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                             0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                             0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
static const double WG[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                             0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

typedef struct {
    int kind;
    const double *d;     /* the row's data */
    long degree;         /* splines */
    Py_ssize_t nk, dim;
    const double *knots, *coef;
    double period;       /* NaN if none */
    double *tri;         /* de Boor scratch: (degree + 1) x dim */
    Py_ssize_t rules;    /* Gauss rules left */
} Curve;

/* |C'(u)|, or NaN. */
static double speed(const Curve *c, double u)
{
    const double *d = c->d;
    double v[3];
    switch (c->kind) {
    case CONIC: {
        double s = -d[9] * sin(u), t = d[10] * cos(u);
        for (int k = 0; k < 3; k++)
            v[k] = s * d[3 + k] + t * d[6 + k];
        break;
    }
    case HYPERBOLA: {
        double s = d[9] * sinh(u), t = d[10] * cosh(u);
        for (int k = 0; k < 3; k++)
            v[k] = s * d[3 + k] + t * d[6 + k];
        break;
    }
    case SPLINE: {
        long p = c->degree;
        Py_ssize_t dim = c->dim, n = c->nk - p - 1;
        const double *knots = c->knots;
        double x = u;
        if (!isnan(c->period)) {
            double start = knots[p], m = fmod(u - start, c->period);
            x = start + (m < 0 ? m + c->period : m);
        }
        Py_ssize_t span = knot_span(knots, c->nk, n, p, x);
        double *t = c->tri;
        for (long j = 0; j <= p; j++)
            for (Py_ssize_t k = 0; k < dim; k++)
                t[j * dim + k] = c->coef[(j + span - p) * dim + k];
        for (long r = 1; r < p; r++) /* all levels but the last: two points remain, t[p - 1] and t[p] */
            for (long j = p; j >= r; j--) {
                double k0 = knots[j + span - p], width = knots[j + 1 + span - r] - k0;
                double alpha = width > 0 ? (x - k0) / width : 0.0;
                for (Py_ssize_t k = 0; k < dim; k++)
                    t[j * dim + k] = (1.0 - alpha) * t[(j - 1) * dim + k] + alpha * t[j * dim + k];
            }
        double width = knots[span + 1] - knots[span];
        if (p < 1 || !(width > 0))
            return NAN;
        double alpha = (x - knots[span]) / width, scale = p / width;
        const double *d0 = t + (p - 1) * dim, *d1 = t + p * dim;
        if (dim == 3) {
            for (int k = 0; k < 3; k++)
                v[k] = scale * (d1[k] - d0[k]);
        } else {
            double w = (1.0 - alpha) * d0[3] + alpha * d1[3], dw = scale * (d1[3] - d0[3]);
            if (!(w != 0))
                return NAN;
            for (int k = 0; k < 3; k++) {
                double a = (1.0 - alpha) * d0[k] + alpha * d1[k], da = scale * (d1[k] - d0[k]);
                v[k] = (da - dw * (a / w)) / w;
            }
        }
        break;
    }
    default:
        return NAN;
    }
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* The 15-point Kronrod estimate of the integral over [a, b]; *err gets its difference from the 7-point
 * Gauss estimate (a bound, pessimistic by orders of magnitude on smooth pieces). */
static double kronrod(Curve *c, double a, double b, double *err)
{
    double h = 0.5 * (b - a), m = 0.5 * (a + b);
    double f0 = speed(c, m), k = WK[7] * f0, g = WG[3] * f0;
    c->rules--;
    for (int i = 0; i < 7; i++) {
        double f = speed(c, m - h * XK[i]) + speed(c, m + h * XK[i]);
        k += WK[i] * f;
        if (i & 1)
            g += WG[i / 2] * f;
    }
    *err = fabs(h * (k - g));
    return h * k;
}

/* The integral over [a, b], whose Kronrod estimate is value with error bound err, to tol (or TOL_REL of
 * itself); NaN if it does not settle. */
static double adapt(Curve *c, double a, double b, double value, double err, double tol, int depth)
{
    if (!isfinite(value))
        return NAN;
    if (err <= dmax(tol, TOL_REL * fabs(value)))
        return value;
    double m = 0.5 * (a + b), e1, e2;
    if (depth >= MAX_DEPTH || c->rules <= 0 || !(a < m && m < b))
        return NAN;
    double v1 = kronrod(c, a, m, &e1), v2 = kronrod(c, m, b, &e2);
    return adapt(c, a, m, v1, e1, 0.5 * tol, depth + 1) + adapt(c, m, b, v2, e2, 0.5 * tol, depth + 1);
}

/* The breakpoints of row e over [a, b] into *out (a and b included); their count, or -1 if out of memory. */
static Py_ssize_t pieces(const Curve *c, double a, double b, const double *hint, Py_ssize_t n_hint, double **out)
{
    if (n_hint >= 2) { /* a periodic spline: its knots over all periods, with a and b */
        *out = malloc(n_hint * sizeof(double));
        if (!*out)
            return -1;
        memcpy(*out, hint, n_hint * sizeof(double));
        return n_hint;
    }
    if (c->kind == SPLINE) {
        double *v = malloc((c->nk + 2) * sizeof(double));
        if (!v)
            return -1;
        Py_ssize_t n = 0;
        v[n++] = a;
        for (Py_ssize_t i = 0; i < c->nk; i++)
            if (c->knots[i] > v[n - 1] && c->knots[i] < b)
                v[n++] = c->knots[i];
        v[n++] = b;
        *out = v;
        return n;
    }
    Py_ssize_t k = (Py_ssize_t)ceil((b - a) / MAX_SPLIT);
    if (k < 1)
        k = 1;
    if (k > 1000000)
        return 0;
    double *v = malloc((k + 1) * sizeof(double));
    if (!v)
        return -1;
    for (Py_ssize_t i = 0; i <= k; i++)
        v[i] = a + (b - a) * ((double)i / k);
    v[k] = b;
    *out = v;
    return k + 1;
}

/* The length of row e over [a, b], NaN where it cannot be had to TOL_REL; -2 if out of memory. */
static double length(const int64_t *kind, const int64_t *gofs, const int64_t *ints, const double *gdata, Py_ssize_t e,
                     double a, double b, const double *hint, Py_ssize_t n_hint)
{
    Curve c = {.kind = (int)kind[e], .d = gdata + gofs[e], .period = NAN, .rules = MAX_RULES};
    if (!(a <= b) || !isfinite(a) || !isfinite(b) || (c.kind != CONIC && c.kind != HYPERBOLA && c.kind != SPLINE))
        return NAN;
    if (a == b)
        return 0.0;
    if (c.kind == SPLINE) {
        c.degree = (long)ints[3 * e];
        c.nk = ints[3 * e + 1];
        c.dim = ints[3 * e + 2];
        c.period = c.d[0];
        c.knots = c.d + 1;
        c.coef = c.d + 1 + c.nk;
        if (c.degree < 1 || (c.dim != 3 && c.dim != 4) || c.nk < 2 * (c.degree + 1))
            return NAN;
        c.tri = malloc((c.degree + 1) * c.dim * sizeof(double));
        if (!c.tri)
            return -2;
    }
    double *v = NULL, total = 0.0;
    Py_ssize_t n = pieces(&c, a, b, hint, n_hint, &v);
    if (n < 0) {
        free(c.tri);
        return -2;
    }
    double *first = malloc(2 * (n > 1 ? n - 1 : 1) * sizeof(double)), scale = 0.0;
    if (!first) {
        free(v);
        free(c.tri);
        return -2;
    }
    for (Py_ssize_t i = 0; i + 1 < n; i++) /* the length to within a few per cent: the tolerances' scale */
        scale += fabs(first[2 * i] = kronrod(&c, v[i], v[i + 1], &first[2 * i + 1]));
    if (n < 2 || !isfinite(scale)) {
        total = NAN;
    } else {
        double tol = TOL_REL * scale;
        for (Py_ssize_t i = 0; i + 1 < n && !isnan(total); i++)
            total += adapt(&c, v[i], v[i + 1], first[2 * i], first[2 * i + 1], tol * (v[i + 1] - v[i]) / (b - a), 0);
    }
    free(first);
    free(v);
    free(c.tri);
    return total;
}

/* edge_lengths(kind, gofs, ints, gdata, hofs, hdata, domain, rows, out): out[k] = the length of row rows[k]
 * over its domain, or NaN where it is not had here (see the file's comment). */
PyObject *ck_edge_lengths(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n_rows, n_dom, m, n_out, n_hofs;
    PyObject *result = NULL;
    const int64_t *kind = ck_arg(&b, args, 0, I64, 0, &n_rows);
    const int64_t *gofs = ck_arg(&b, args, 1, I64, 0, NULL);
    const int64_t *ints = ck_arg(&b, args, 2, I64, 0, NULL);
    const double *gdata = ck_arg(&b, args, 3, F64, 0, NULL);
    const int64_t *hofs = ck_arg(&b, args, 4, I64, 0, &n_hofs);
    const double *hdata = ck_arg(&b, args, 5, F64, 0, NULL);
    const double *domain = ck_arg(&b, args, 6, F64, 0, &n_dom);
    const int64_t *rows = ck_arg(&b, args, 7, I64, 0, &m);
    double *out = ck_arg(&b, args, 8, F64, 1, &n_out);
    if (!out)
        goto done;
    if (n_dom != 2 * n_rows || n_hofs != n_rows + 1 || n_out != m) {
        PyErr_SetString(PyExc_ValueError, "edge_lengths: inconsistent table, domain, rows or output");
        goto done;
    }
    for (Py_ssize_t k = 0; k < m; k++) {
        Py_ssize_t e = rows[k];
        if (e < 0 || e >= n_rows) {
            PyErr_SetString(PyExc_IndexError, "edge_lengths: row out of range");
            goto done;
        }
        out[k] = length(kind, gofs, ints, gdata, e, domain[2 * e], domain[2 * e + 1], hdata + hofs[e],
                        hofs[e + 1] - hofs[e]);
        if (out[k] == -2) {
            PyErr_NoMemory();
            goto done;
        }
    }
    result = Py_None;
    Py_INCREF(result);
done:
    ck_release(&b);
    return result;
}
