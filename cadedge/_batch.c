/* Target-mode refinement of many edges in one call, from their geometry in flat arrays.
 *
 * refine_shape used to run, per edge, a few hundred Python-level steps (the exploration's levels, the
 * node search, the equidistribution trials, each a handful of numpy calls on short arrays) that cost
 * 30-60x one OCCT pass. Here the same steps run in C over every edge whose curve is a line, circle,
 * ellipse, B-spline or Bezier curve, evaluated from its definition (cadedge/occt/edgetable.py reads the
 * geometry and checks it against OCCT). The arithmetic follows the Python path operation by operation,
 * numpy's pairwise summation included, so the grids are the same; an edge this path cannot finish as the
 * Python path would (a zero-length curve, the sampling cap, a missed target: all cases that add a note)
 * is reported back and refined by the Python path.
 *
 * Geometry table (cadedge/occt/edgetable.py): kind[e] (LINE, CONIC, SPLINE, HYPERBOLA), its data at gdata[gofs[e]:]:
 *   line:   location (3), direction (3)                     point = loc + u dir
 *   conic:  location, x, y (3 each), rx, ry                 point = loc + rx cos(u) x + ry sin(u) y
 *   hyperbola: as a conic                                   point = rx cosh(u) x + ry sinh(u) y + loc
 *           (in OCCT's order of operations, ElCLib::HyperbolaValue: the per-edge path evaluates it by OCCT)
 *   spline: period (NaN if none), knots (nk), coefficients ((nk - degree - 1) x dim), dim 3 or 4 (rational,
 *           homogeneous), with ints[e] = (degree, nk, dim); a periodic spline is wrapped into its first period.
 */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "_bintools.h"
#include "_kernels.h"

enum { LINE = 0, CONIC = 1, SPLINE = 2, HYPERBOLA = 3 };
enum { OK = 0, PYTHON_PATH = 1 };

typedef struct {
    const int64_t *kind, *gofs, *ints;
    const double *gdata;
} Geometry;

/* ---------------------------------------------------------------- growable arrays */

/* Vec, vec_reserve and vec_push: _bintools.h */

/* ---------------------------------------------------------------- numpy's arithmetic */

/* np.sum of a float64 array: numpy's pairwise summation. */
static double pairwise(const double *a, Py_ssize_t n)
{
    if (n < 8) {
        double res = 0.;
        for (Py_ssize_t i = 0; i < n; i++)
            res += a[i];
        return res;
    }
    if (n <= 128) {
        double r[8];
        Py_ssize_t i;
        for (int j = 0; j < 8; j++)
            r[j] = a[j];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; j++)
                r[j] += a[i + j];
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; i++)
            res += a[i];
        return res;
    }
    Py_ssize_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise(a, n2) + pairwise(a + n2, n - n2);
}

/* cadedge.grid.row_norms of p[j] - p[i]: numpy's einsum adds the squares as (x x + z z) + y y. */
static inline double row_norm(const double *p, Py_ssize_t i, Py_ssize_t j)
{
    double dx = p[3 * j] - p[3 * i], dy = p[3 * j + 1] - p[3 * i + 1], dz = p[3 * j + 2] - p[3 * i + 2];
    return sqrt((dx * dx + dz * dz) + dy * dy);
}

/* cadedge.grid.polyline_length of n points; scratch holds n doubles. */
static double polyline(const double *p, Py_ssize_t n, double *scratch)
{
    for (Py_ssize_t i = 0; i + 1 < n; i++)
        scratch[i] = row_norm(p, i, i + 1);
    return 0.0 + pairwise(scratch, n > 0 ? n - 1 : 0);
}

/* np.mod(a, b) for float64. */
static double pymod(double a, double b)
{
    double mod = fmod(a, b);
    if (!b)
        return mod;
    if (mod) {
        if ((b < 0) != (mod < 0))
            mod += b;
    } else {
        mod = copysign(0.0, b);
    }
    return mod;
}

/* First index with a[i] >= x (np.searchsorted, side="left"). */
static Py_ssize_t search_left(const double *a, Py_ssize_t n, double x)
{
    Py_ssize_t lo = 0, hi = n;
    while (lo < hi) {
        Py_ssize_t mid = (lo + hi) / 2;
        if (a[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Sort v[0:n] and drop repeats (cadedge.grid.unique_sorted); returns the new count. */
static Py_ssize_t unique_sorted(double *v, Py_ssize_t n)
{
    if (n < 2)
        return n;
    qsort(v, n, sizeof(double), cmp_double);
    Py_ssize_t w = 1;
    for (Py_ssize_t i = 1; i < n; i++)
        if (v[i] != v[w - 1])
            v[w++] = v[i];
    return w;
}

/* ---------------------------------------------------------------- evaluation */

/* True when all n values are finite (the per-edge path's Evaluator raises on any other). */
static int all_finite(const double *v, Py_ssize_t n)
{
    for (Py_ssize_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* Points of edge e at u[0:m] into out (m x 3); 0, or -1 if out of memory. */
static int evaluate(const Geometry *g, Py_ssize_t e, const double *u, Py_ssize_t m, double *out)
{
    const double *d = g->gdata + g->gofs[e];
    switch (g->kind[e]) {
    case LINE:
        for (Py_ssize_t i = 0; i < m; i++)
            for (int c = 0; c < 3; c++)
                out[3 * i + c] = d[c] + u[i] * d[3 + c];
        return 0;
    case CONIC:
        for (Py_ssize_t i = 0; i < m; i++) {
            double cu = d[9] * cos(u[i]), su = d[10] * sin(u[i]);
            for (int c = 0; c < 3; c++)
                out[3 * i + c] = d[c] + cu * d[3 + c] + su * d[6 + c];
        }
        return 0;
    case HYPERBOLA:
        for (Py_ssize_t i = 0; i < m; i++) {
            double a1 = d[9] * cosh(u[i]), a2 = d[10] * sinh(u[i]);
            for (int c = 0; c < 3; c++)
                out[3 * i + c] = a1 * d[3 + c] + a2 * d[6 + c] + d[c];
        }
        return 0;
    default: {
        long degree = (long)g->ints[3 * e];
        Py_ssize_t nk = g->ints[3 * e + 1], dim = g->ints[3 * e + 2];
        double period = d[0];
        const double *knots = d + 1, *coef = d + 1 + nk;
        double *buf = malloc(m * (dim + 1) * sizeof(double) + 1);
        if (!buf)
            return -1;
        double *w = buf, *h = buf + m;
        if (isnan(period)) {
            memcpy(w, u, m * sizeof(double));
        } else {
            double start = knots[degree];
            for (Py_ssize_t i = 0; i < m; i++)
                w[i] = start + pymod(u[i] - start, period);
        }
        int status = ck_de_boor(knots, nk, coef, nk - degree - 1, dim, w, m, dim == 3 ? out : h, degree);
        if (status == 0 && dim == 4)
            for (Py_ssize_t i = 0; i < m; i++)
                for (int c = 0; c < 3; c++)
                    out[3 * i + c] = h[4 * i + c] / h[4 * i + 3];
        free(buf);
        return status;
    }
    }
}

/* evaluate_edges(kind, gofs, ints, gdata, edge, u, out): out[i] = point of edge[i] at u[i]. */
PyObject *ck_evaluate_edges(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n_edges, m, n_out;
    Geometry g;
    PyObject *result = NULL;
    g.kind = ck_arg(&b, args, 0, I64, 0, &n_edges);
    g.gofs = ck_arg(&b, args, 1, I64, 0, NULL);
    g.ints = ck_arg(&b, args, 2, I64, 0, NULL);
    g.gdata = ck_arg(&b, args, 3, F64, 0, NULL);
    const int64_t *edge = ck_arg(&b, args, 4, I64, 0, &m);
    const double *u = ck_arg(&b, args, 5, F64, 0, NULL);
    double *out = ck_arg(&b, args, 6, F64, 1, &n_out);
    if (!out)
        goto done;
    if (n_out != 3 * m) {
        PyErr_SetString(PyExc_ValueError, "evaluate_edges: out must be (len(u), 3)");
        goto done;
    }
    for (Py_ssize_t i = 0; i < m;) {
        Py_ssize_t j = i + 1;
        while (j < m && edge[j] == edge[i])
            j++;
        if (edge[i] < 0 || edge[i] >= n_edges) {
            PyErr_SetString(PyExc_IndexError, "evaluate_edges: edge index out of range");
            goto done;
        }
        if (evaluate(&g, edge[i], u + i, j - i, out + 3 * i) < 0) {
            PyErr_NoMemory();
            goto done;
        }
        i = j;
    }
    result = Py_None;
    Py_INCREF(result);
done:
    ck_release(&b);
    return result;
}

/* ---------------------------------------------------------------- one edge */

typedef struct {
    double explore_share, margin, exact_margin, agreement, straight, asymptotic, noise_share;
    Py_ssize_t max_trials, max_samples, conic_roots, span_roots, default_roots;
} Settings;

typedef struct {
    double ald, exact, a, b;
    const double *first, *last; /* vertex points */
    const double *hint;         /* distinct knots with a and b (periodic splines), or NULL */
    Py_ssize_t n_hint;
} Job;

typedef struct {
    Vec params, points;
    double estimate, raw_estimate;
    int64_t evaluations;
} Result;

typedef struct {
    double u;
    Py_ssize_t at;
} Sample;

/* a before b: by parameter, then by position (a total order: any sort gives the same result) */
static inline int sample_before(const Sample *a, const Sample *b)
{
    return a->u < b->u || (a->u == b->u && a->at < b->at);
}

/* Sort s[0:n] (tmp: room for n more): runs of 8 by insertion, then merged bottom-up. qsort's comparison
 * through a function pointer cost more than the rest of the exploration's bookkeeping. */
static void sort_samples(Sample *s, Sample *tmp, Py_ssize_t n)
{
    for (Py_ssize_t lo = 0; lo < n; lo += 8) {
        Py_ssize_t hi = lo + 8 < n ? lo + 8 : n;
        for (Py_ssize_t i = lo + 1; i < hi; i++) {
            Sample x = s[i];
            Py_ssize_t j = i;
            for (; j > lo && sample_before(&x, &s[j - 1]); j--)
                s[j] = s[j - 1];
            s[j] = x;
        }
    }
    Sample *from = s, *to = tmp;
    for (Py_ssize_t width = 8; width < n; width *= 2) {
        for (Py_ssize_t lo = 0; lo < n; lo += 2 * width) {
            Py_ssize_t mid = lo + width < n ? lo + width : n, hi = lo + 2 * width < n ? lo + 2 * width : n;
            Py_ssize_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi)
                to[k++] = sample_before(&from[j], &from[i]) ? from[j++] : from[i++];
            while (i < mid)
                to[k++] = from[i++];
            while (j < hi)
                to[k++] = from[j++];
        }
        Sample *t = from;
        from = to, to = t;
    }
    if (from != s)
        memcpy(s, from, n * sizeof(Sample));
}

/* The roots of the exploration (cadedge.explore.root_params with EdgeCurve.initial_params) into *out. */
static Py_ssize_t roots(const Geometry *g, Py_ssize_t e, const Job *job, const Settings *s, double **out)
{
    double a = job->a, b = job->b;
    Py_ssize_t cap, n = 0;
    double *r;
    if (g->kind[e] == LINE) {
        r = malloc(2 * sizeof(double));
        if (!r)
            return -1;
        r[n++] = a, r[n++] = b;
    } else if (g->kind[e] == CONIC || g->kind[e] == HYPERBOLA) { /* uniform steps: a few per turn, or default_roots */
        double steps = ceil((double)s->conic_roots * (b - a) / (2 * M_PI));
        Py_ssize_t num = g->kind[e] == HYPERBOLA ? s->default_roots + 1 : (Py_ssize_t)(steps > 2 ? steps : 2) + 1;
        r = malloc((num + 2) * sizeof(double));
        if (!r)
            return -1;
        double step = (b - a) / (double)(num - 1);
        r[n++] = a;
        for (Py_ssize_t i = 0; i < num; i++) {
            double v = i == num - 1 ? b : (double)i * step + a;
            r[n++] = v < a ? a : (v > b ? b : v);
        }
        r[n++] = b;
    } else {
        const double *d = g->gdata + g->gofs[e];
        Py_ssize_t nk = g->ints[3 * e + 1];
        double *k = malloc((nk + 2 + job->n_hint) * sizeof(double));
        if (!k)
            return -1;
        Py_ssize_t nkn = 0;
        if (job->hint) {
            memcpy(k, job->hint, job->n_hint * sizeof(double));
            nkn = job->n_hint;
        } else {
            double tol = 1e-9 * (b - a);
            k[nkn++] = a;
            for (Py_ssize_t i = 0; i < nk; i++) {
                double x = d[1 + i];
                if ((i == 0 || x != d[i]) && x > a + tol && x < b - tol)
                    k[nkn++] = x;
            }
            k[nkn++] = b;
        }
        cap = (nkn - 1) * s->span_roots + 3;
        r = malloc(cap * sizeof(double));
        if (!r) {
            free(k);
            return -1;
        }
        r[n++] = a;
        for (Py_ssize_t i = 0; i + 1 < nkn; i++) {
            double width = k[i + 1] - k[i];
            for (Py_ssize_t j = 0; j < s->span_roots; j++) {
                double x = k[i] + width * ((double)j / (double)s->span_roots);
                r[n++] = x < a ? a : (x > b ? b : x);
            }
        }
        r[n++] = b < a ? a : b;
        r[n++] = b;
        free(k);
    }
    *out = r;
    return unique_sorted(r, n);
}

/* The exploration (cadedge.explore.explore): sorted distinct samples u, p (n), corners, remainder. */
typedef struct {
    double *u, *p, *corners;
    Py_ssize_t n, n_corners;
    double remainder, length;
    int64_t evaluations;
} Explored;

static void free_explored(Explored *x)
{
    free(x->u), free(x->p), free(x->corners);
    x->u = x->p = x->corners = NULL;
}

#define TRY(cond)                                                                                           \
    do {                                                                                                    \
        if (!(cond))                                                                                        \
            goto fail;                                                                                      \
    } while (0)

/* Returns OK, PYTHON_PATH (the Python path would add a note) or -1 (out of memory). */
static int explore(const Geometry *g, Py_ssize_t e, const Job *job, const Settings *s, Explored *x)
{
    int status = -1;
    double *ua = NULL, *t = NULL, *q = NULL, *pq = NULL, *c = NULL, *gains = NULL, *corners = NULL;
    int64_t *split = NULL;
    Sample *order = NULL;
    Vec U = {0}, P = {0}, C = {0};
    memset(x, 0, sizeof *x);
    Py_ssize_t nr = roots(g, e, job, s, &ua);
    TRY(nr >= 0);
    if (nr < 2) { /* a degenerate domain: the Python path says so */
        free(ua);
        return PYTHON_PATH;
    }
    Py_ssize_t live = nr - 1, nfirst = 2 * nr - 1;
    TRY(vec_reserve(&U, nfirst) == 0 && vec_reserve(&P, 3 * nfirst) == 0);
    memcpy(U.d, ua, nr * sizeof(double));
    for (Py_ssize_t i = 0; i < live; i++)
        U.d[nr + i] = 0.5 * (ua[i] + ua[i + 1]);
    U.n = nfirst, P.n = 3 * nfirst;
    TRY(evaluate(g, e, U.d, nfirst, P.d) == 0);
    x->evaluations = nfirst;
    double biggest = 0.0;
    for (Py_ssize_t i = 0; i < 3 * nfirst; i++)
        biggest = dmax(biggest, fabs(P.d[i]));
    double min_width = 1e-12 * (job->b - job->a), noise = s->noise_share * biggest;
    double tol = job->ald * s->explore_share;
    /* live triples: ua um ub ratio (4 per triple) and pa pm pb (9 per triple), in t */
    TRY(t = malloc(13 * live * sizeof(double)));
    double *tu = t, *tm = t + live, *tb = t + 2 * live, *tr = t + 3 * live, *tpa = t + 4 * live,
           *tpm = tpa + 3 * live, *tpb = tpm + 3 * live;
    for (Py_ssize_t i = 0; i < live; i++) {
        tu[i] = U.d[i], tb[i] = U.d[i + 1], tm[i] = U.d[nr + i], tr[i] = NAN;
        for (int k = 0; k < 3; k++)
            tpa[3 * i + k] = P.d[3 * i + k], tpb[3 * i + k] = P.d[3 * (i + 1) + k], tpm[3 * i + k] = P.d[3 * (nr + i) + k];
    }
    double remainder = 0.0, scale = -1.0;
    Py_ssize_t samples = nfirst;
    while (live) {
        TRY(corners = malloc(live * sizeof(double)));
        TRY(split = malloc(live * sizeof(int64_t)));
        TRY(gains = malloc(live * sizeof(double)));
        Py_ssize_t n_corners;
        double rem;
        Py_ssize_t n_split = ck_classify(live, tu, tm, tb, tpa, tpm, tpb, tr, tol, &scale, min_width, noise, s->straight,
                                         s->asymptotic, corners, &n_corners, split, gains, &rem);
        TRY(n_split >= 0);
        remainder += rem;
        TRY(vec_push(&C, corners, n_corners) == 0);
        free(corners), corners = NULL;
        if (!n_split)
            break;
        if (samples + 2 * n_split > s->max_samples) {
            status = PYTHON_PATH;
            goto fail;
        }
        TRY(q = malloc(2 * n_split * sizeof(double)));
        TRY(pq = malloc(6 * n_split * sizeof(double)));
        for (Py_ssize_t k = 0; k < n_split; k++) {
            Py_ssize_t i = split[k];
            q[2 * k] = 0.5 * (tu[i] + tm[i]);
            q[2 * k + 1] = 0.5 * (tm[i] + tb[i]);
        }
        TRY(evaluate(g, e, q, 2 * n_split, pq) == 0);
        samples += 2 * n_split, x->evaluations += 2 * n_split;
        TRY(vec_push(&U, q, 2 * n_split) == 0 && vec_push(&P, pq, 6 * n_split) == 0);
        Py_ssize_t next = 2 * n_split;
        TRY(c = malloc(13 * next * sizeof(double)));
        double *cu = c, *cm = c + next, *cb = c + 2 * next, *cr = c + 3 * next, *cpa = c + 4 * next,
               *cpm = cpa + 3 * next, *cpb = cpm + 3 * next;
        ck_children(n_split, tu, tm, tb, tpa, tpm, tpb, split, gains, q, pq, cu, cm, cb, cpa, cpm, cpb, cr);
        free(t), free(q), free(pq), free(split), free(gains);
        q = pq = gains = NULL, split = NULL;
        t = c, c = NULL, live = next;
        tu = cu, tm = cm, tb = cb, tr = cr, tpa = cpa, tpm = cpm, tpb = cpb;
    }
    /* sorted by parameter, the first of a repeated parameter kept (explore._sorted_unique) */
    Py_ssize_t total = U.n;
    TRY(order = malloc(2 * total * sizeof(Sample)));
    for (Py_ssize_t i = 0; i < total; i++)
        order[i].u = U.d[i], order[i].at = i;
    sort_samples(order, order + total, total);
    TRY(x->u = malloc(total * sizeof(double)));
    TRY(x->p = malloc(3 * total * sizeof(double)));
    Py_ssize_t n = 0;
    for (Py_ssize_t i = 0; i < total; i++) {
        if (n && !(order[i].u > x->u[n - 1]))
            continue;
        x->u[n] = order[i].u;
        memcpy(x->p + 3 * n, P.d + 3 * order[i].at, 3 * sizeof(double));
        n++;
    }
    x->n = n;
    if (!all_finite(x->p, 3 * n)) { /* the per-edge path reports the parameter */
        status = PYTHON_PATH;
        goto fail;
    }
    TRY(x->corners = malloc((C.n ? C.n : 1) * sizeof(double)));
    memcpy(x->corners, C.d, C.n * sizeof(double));
    x->n_corners = unique_sorted(x->corners, C.n);
    double *scratch = malloc(n * sizeof(double));
    TRY(scratch);
    x->length = polyline(x->p, n, scratch) + remainder;
    free(scratch);
    x->remainder = remainder;
    status = OK;
fail:
    free(ua), free(t), free(q), free(pq), free(c), free(gains), free(corners), free(split), free(order);
    free(U.d), free(P.d), free(C.d);
    if (status != OK)
        free_explored(x);
    return status;
}

/* splitting.evaluate_new: points at params (m), from the samples where a parameter is one; counts the rest.
 * Returns 0, 1 for a non-finite point or -1 if out of memory. */
static int evaluate_new(const Geometry *g, Py_ssize_t e, const Explored *x, const double *params, Py_ssize_t m,
                        double *out, int64_t *evaluations)
{
    double *want = malloc(4 * m * sizeof(double) + 1);
    if (!want)
        return -1;
    double *got = want + m;
    Py_ssize_t *slot = malloc(m * sizeof(Py_ssize_t) + 1), k = 0;
    if (!slot) {
        free(want);
        return -1;
    }
    for (Py_ssize_t i = 0; i < m; i++) {
        Py_ssize_t j = search_left(x->u, x->n, params[i]);
        if (j > x->n - 1)
            j = x->n - 1;
        if (x->u[j] == params[i]) {
            memcpy(out + 3 * i, x->p + 3 * j, 3 * sizeof(double));
        } else {
            want[k] = params[i], slot[k++] = i;
        }
    }
    int status = 0;
    if (k) {
        status = evaluate(g, e, want, k, got);
        if (status == 0 && !all_finite(got, 3 * k))
            status = 1;
        for (Py_ssize_t i = 0; i < k && status == 0; i++)
            memcpy(out + 3 * slot[i], got + 3 * i, 3 * sizeof(double));
        *evaluations += k;
    }
    free(want), free(slot);
    return status;
}

/* placement.equidistribute: count segments' worth of parameters into *out, allocated here (returns the count,
 * -1 if out of memory). */
static Py_ssize_t equidistribute(const Explored *x, const double *cum, const double *measure, const int64_t *cidx,
                                 Py_ssize_t nc, Py_ssize_t count, double **out)
{
    Py_ssize_t last = x->n - 1, pieces, size;
    int64_t *cut = malloc((nc + 2) * sizeof(int64_t)), *alloc = malloc((nc + 2) * sizeof(int64_t));
    double *raw = malloc((nc + 2) * sizeof(double)), *share = malloc((nc + 2) * sizeof(double));
    Py_ssize_t result = -1;
    if (!cut || !alloc || !raw || !share)
        goto done;
    if (!nc) {
        cut[0] = 0, cut[1] = last, pieces = 1;
        alloc[0] = measure[last] > measure[0] ? (count > 1 ? count : 1) : 1;
    } else {
        /* cut = unique_sorted([0, corners..., last]): the corners are sorted sample indices */
        Py_ssize_t w = 0;
        cut[w++] = 0;
        for (Py_ssize_t i = 0; i < nc; i++)
            if (cidx[i] != cut[w - 1])
                cut[w++] = cidx[i];
        if (cut[w - 1] != last)
            cut[w++] = last;
        pieces = w - 1;
        for (Py_ssize_t i = 0; i < pieces; i++)
            share[i] = measure[cut[i + 1]] - measure[cut[i]];
        double total = 0.0 + pairwise(share, pieces);
        Py_ssize_t want = count > pieces ? count : pieces;
        if (total <= 0) {
            for (Py_ssize_t i = 0; i < pieces; i++)
                alloc[i] = 1;
        } else {
            int64_t sum = 0;
            for (Py_ssize_t i = 0; i < pieces; i++) {
                raw[i] = share[i] / total * (double)want;
                double f = floor(raw[i]);
                alloc[i] = f > 1 ? (int64_t)f : 1;
                sum += alloc[i];
            }
            /* the pieces with the largest fractions left get one more each (a stable order on ties) */
            for (int64_t short_ = want - sum; short_ > 0; short_--) {
                Py_ssize_t best = -1;
                for (Py_ssize_t i = 0; i < pieces; i++) {
                    if (raw[i] == INFINITY)
                        continue;
                    if (best < 0 || -(raw[i] - alloc[i]) < -(raw[best] - alloc[best]))
                        best = i;
                }
                if (best < 0)
                    break;
                alloc[best] += 1;
                raw[best] = INFINITY; /* taken: numpy adds one to each of the first `short` of the order */
            }
        }
    }
    size = 1;
    for (Py_ssize_t i = 0; i < pieces; i++)
        size += alloc[i] > 1 ? alloc[i] : 1;
    *out = malloc(size * sizeof(double));
    if (*out)
        result = ck_place(x->u, cum, measure, cut, alloc, pieces, *out, size);
done:
    free(cut), free(alloc), free(raw), free(share);
    return result;
}

/* The fewest of the equidistributed placements that meets the limit (target._equidistributed): its
 * parameters and points in *params, *points (allocated here), or a count of 0 for none; -1 if out of
 * memory, -2 for what the per-edge path must do (a count too large to place here, a non-finite point). */
static Py_ssize_t equidistributed(const Geometry *g, Py_ssize_t e, const Explored *x, const double *cum,
                                  const int64_t *cidx, Py_ssize_t nc, double total, double limit, double budget,
                                  const Settings *s, double **params, double **points, int64_t *evaluations)
{
    Py_ssize_t result = -1, best_count = 0, min_segments = nc + 1;
    double *measure = malloc(x->n * sizeof(double)), *scratch = NULL, *try_u = NULL, *try_p = NULL;
    *params = *points = NULL;
    if (!measure || ck_deficit_measure(x->p, cum, x->n, cidx, nc, measure) < 0)
        goto done;
    double m_tot = measure[x->n - 1];
    double first = budget > 0 && m_tot > 0 ? ceil(sqrt(pow(m_tot, 3.0) / budget)) : (double)min_segments;
    if (first > 1e7) {
        result = -2;
        goto done;
    }
    int64_t n = (int64_t)first > min_segments ? (int64_t)first : min_segments;
    double fixed = limit - budget;
    int64_t lo = min_segments - 1, hi = -1;
    for (Py_ssize_t trial = 0; trial < s->max_trials; trial++) {
        Py_ssize_t m = equidistribute(x, cum, measure, cidx, nc, n, &try_u);
        if (m < 0 || !(try_p = malloc(3 * m * sizeof(double))) || !(scratch = malloc(m * sizeof(double))))
            goto done;
        int got = evaluate_new(g, e, x, try_u, m, try_p, evaluations);
        if (got) {
            result = got > 0 ? -2 : -1;
            goto done;
        }
        double miss = total - polyline(try_p, m, scratch);
        free(scratch), scratch = NULL;
        double predicted = budget > 0 ? ceil((double)n * sqrt(dmax(miss - fixed, 0.0) / budget)) : (double)(n + 1);
        if (miss <= limit) {
            hi = n;
            free(*params), free(*points);
            *params = try_u, *points = try_p, best_count = m;
            try_u = try_p = NULL;
            double down = predicted < (double)(n - 1) ? predicted : (double)(n - 1);
            n = (double)(lo + 1) > down ? lo + 1 : (int64_t)down;
        } else {
            free(try_u), free(try_p);
            try_u = try_p = NULL;
            lo = n;
            double up = predicted < 2.0 * (double)n ? predicted : 2.0 * (double)n;
            n = (double)(n + 1) > up ? n + 1 : (int64_t)up;
            if (hi >= 0 && n > hi - 1)
                n = hi - 1;
        }
        if (hi >= 0 && hi - lo <= 1)
            break;
        if (n > 10000000) {
            result = -2;
            goto done;
        }
    }
    result = best_count;
done:
    free(measure), free(scratch), free(try_u), free(try_p);
    if (result <= 0) {
        free(*params), free(*points);
        *params = *points = NULL;
    }
    return result;
}

/* target.refine_target (without min/max length or growth) and shape._anchor for one edge into r.
 * Returns OK, PYTHON_PATH or -1 (out of memory). */
static int refine_one(const Geometry *g, Py_ssize_t e, const Job *job, const Settings *s, Result *r)
{
    Explored x;
    int status = explore(g, e, job, s, &x);
    if (status != OK)
        return status;
    status = -1;
    double *cum = NULL, *scratch = NULL, *eq_u = NULL, *eq_p = NULL, *pts = NULL;
    int64_t *cidx = NULL, *stops = NULL, *nodes = NULL;
    uint8_t *fixed = NULL;
    Py_ssize_t n = x.n;
    r->evaluations = x.evaluations;
    double total = x.length;
    if (!(total > 0.0)) {
        status = PYTHON_PATH;
        goto fail;
    }
    TRY(cum = malloc(n * sizeof(double)));
    TRY(scratch = malloc(n * sizeof(double)));
    cum[0] = 0.0;
    for (Py_ssize_t i = 0; i + 1 < n; i++) /* np.cumsum: sequential */
        cum[i + 1] = cum[i] + row_norm(x.p, i, i + 1);
    double remainder, limit, exact = job->exact, ald = job->ald;
    if (!isnan(exact) && exact > 0.0 && fabs(exact - total) <= s->agreement * ald * exact) {
        total = exact;
        remainder = dmax(total - cum[n - 1], 0.0);
        limit = ald * (1.0 - s->exact_margin) * total;
    } else {
        remainder = x.remainder;
        limit = ald * (1.0 - s->margin) * total;
    }
    double budget = dmax(limit - remainder, 0.0);
    Py_ssize_t nc = x.n_corners;
    TRY(cidx = malloc((nc + 1) * sizeof(int64_t)));
    TRY(stops = malloc((nc + 1) * sizeof(int64_t)));
    TRY(fixed = calloc(n, 1));
    TRY(nodes = malloc(n * sizeof(int64_t)));
    Py_ssize_t n_stops = 0;
    for (Py_ssize_t i = 0; i < nc; i++) {
        cidx[i] = search_left(x.u, n, x.corners[i]);
        fixed[cidx[i]] = 1;
    }
    for (Py_ssize_t i = 0; i < nc; i++) /* unique_sorted(append(corners, n - 1)); corners are increasing */
        if (!n_stops || cidx[i] != stops[n_stops - 1])
            stops[n_stops++] = cidx[i];
    if (!n_stops || stops[n_stops - 1] != n - 1) {
        if (n_stops && stops[n_stops - 1] > n - 1) { /* a corner past the last sample cannot happen */
            status = PYTHON_PATH;
            goto fail;
        }
        stops[n_stops++] = n - 1;
    }
    /* (no dropping: the equidistributed placement below competes, as in cadedge.target) */
    Py_ssize_t count = ck_fewest(x.p, cum, n, stops, fixed, nodes, budget, 0.0, INFINITY, 0);
    TRY(count >= 0);
    TRY(pts = malloc(3 * count * sizeof(double)));
    for (Py_ssize_t k = 0; k < count; k++)
        memcpy(pts + 3 * k, x.p + 3 * nodes[k], 3 * sizeof(double));
    Py_ssize_t m = equidistributed(g, e, &x, cum, cidx, nc, total, limit, budget, s, &eq_u, &eq_p, &r->evaluations);
    if (m == -2) {
        status = PYTHON_PATH;
        goto fail;
    }
    TRY(m >= 0);
    double *params_out, *points_out;
    Py_ssize_t size;
    if (m > n) { /* scratch space for m points' segments */
        double *more = realloc(cum, m * sizeof(double));
        TRY(more);
        cum = more;
    }
    if (m > 0 && (m < count || (m == count && polyline(eq_p, m, cum) > polyline(pts, count, cum)))) {
        params_out = eq_u, points_out = eq_p, size = m;
    } else {
        for (Py_ssize_t k = 0; k < count; k++)
            scratch[k] = x.u[nodes[k]];
        params_out = scratch, points_out = pts, size = count;
    }
    double length = polyline(points_out, size, cum); /* cum is no longer needed: scratch space */
    double estimate = dmax(1.0 - length / total, 0.0);
    if (estimate > ald) {
        status = PYTHON_PATH;
        goto fail;
    }
    r->raw_estimate = estimate;
    TRY(vec_push(&r->params, params_out, size) == 0 && vec_push(&r->points, points_out, 3 * size) == 0);
    double *anchored = r->points.d + r->points.n - 3 * size;
    memcpy(anchored, job->first, 3 * sizeof(double));
    memcpy(anchored + 3 * (size - 1), job->last, 3 * sizeof(double));
    r->estimate = estimate;
    if (length > 0.0 && estimate < 1.0) {
        double whole = length / (1.0 - estimate);
        r->estimate = dmax(1.0 - polyline(anchored, size, cum) / whole, 0.0);
    }
    status = OK;
fail:
    free_explored(&x);
    free(cum), free(scratch), free(eq_u), free(eq_p), free(pts), free(cidx), free(stops), free(nodes), free(fixed);
    return status;
}

/* refine_edges(kind, gofs, ints, gdata, hofs, hdata, domain, ald, exact, first, last, settings)
 *   -> (status, offsets, params, points, estimate, raw_estimate, evaluations), each a bytearray of int64 or float64
 * Target mode for every edge of the table: domain (E x 2), ald (E), exact (E, its length or NaN), first and
 * last (E x 3, the vertex points its grid ends on), hint knots at hdata[hofs[e]:hofs[e + 1]] (periodic
 * splines), settings (the constants of cadedge.target and cadedge.explore, see cadedge/batchrefine.py).
 * Edge e's grid is params[offsets[e]:offsets[e + 1]] where status[e] is 0; status 1 asks for the Python
 * path. estimate is after anchoring the ends, raw_estimate before. */
PyObject *ck_refine_edges(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t n_edges, n_settings;
    Geometry g;
    PyObject *result = NULL;
    Result r = {0};
    int64_t *status = NULL, *offsets = NULL, *evaluations = NULL;
    double *estimate = NULL, *raw = NULL;
    g.kind = ck_arg(&b, args, 0, I64, 0, &n_edges);
    g.gofs = ck_arg(&b, args, 1, I64, 0, NULL);
    g.ints = ck_arg(&b, args, 2, I64, 0, NULL);
    g.gdata = ck_arg(&b, args, 3, F64, 0, NULL);
    const int64_t *hofs = ck_arg(&b, args, 4, I64, 0, NULL);
    const double *hdata = ck_arg(&b, args, 5, F64, 0, NULL);
    const double *domain = ck_arg(&b, args, 6, F64, 0, NULL);
    const double *ald = ck_arg(&b, args, 7, F64, 0, NULL);
    const double *exact = ck_arg(&b, args, 8, F64, 0, NULL);
    const double *first = ck_arg(&b, args, 9, F64, 0, NULL);
    const double *last = ck_arg(&b, args, 10, F64, 0, NULL);
    const double *set = ck_arg(&b, args, 11, F64, 0, &n_settings);
    if (!set)
        goto done;
    if (n_settings != 12) {
        PyErr_SetString(PyExc_ValueError, "refine_edges: 12 settings expected");
        goto done;
    }
    Settings s = {set[0], set[1], set[2], set[3], set[4], set[5], set[6],
                  (Py_ssize_t)set[7], (Py_ssize_t)set[8], (Py_ssize_t)set[9], (Py_ssize_t)set[10], (Py_ssize_t)set[11]};
    status = calloc(n_edges + 1, sizeof(int64_t));
    offsets = calloc(n_edges + 1, sizeof(int64_t));
    evaluations = calloc(n_edges + 1, sizeof(int64_t));
    estimate = calloc(n_edges + 1, sizeof(double));
    raw = calloc(n_edges + 1, sizeof(double));
    if (!status || !offsets || !evaluations || !estimate || !raw) {
        PyErr_NoMemory();
        goto done;
    }
    for (Py_ssize_t e = 0; e < n_edges; e++) {
        Job job = {ald[e], exact[e], domain[2 * e], domain[2 * e + 1], first + 3 * e, last + 3 * e,
                   hofs[e + 1] > hofs[e] ? hdata + hofs[e] : NULL, hofs[e + 1] - hofs[e]};
        r.evaluations = 0;
        int st = refine_one(&g, e, &job, &s, &r);
        if (st < 0) {
            PyErr_NoMemory();
            goto done;
        }
        status[e] = st, evaluations[e] = r.evaluations, estimate[e] = r.estimate, raw[e] = r.raw_estimate;
        offsets[e + 1] = r.params.n;
    }
    result = Py_BuildValue("(NNNNNNN)", as_bytes(status, n_edges * 8), as_bytes(offsets, (n_edges + 1) * 8),
                           as_bytes(r.params.d, r.params.n * 8), as_bytes(r.points.d, r.points.n * 8),
                           as_bytes(estimate, n_edges * 8), as_bytes(raw, n_edges * 8),
                           as_bytes(evaluations, n_edges * 8));
done:
    free(status), free(offsets), free(evaluations), free(estimate), free(raw), free(r.params.d), free(r.points.d);
    ck_release(&b);
    return result;
}
