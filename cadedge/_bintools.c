/* OCCT's binary curves and surfaces (BinTools_CurveSet, BinTools_Curve2dSet, BinTools_SurfaceSet): the
 * 3-D curves the edge table evaluates parsed into its rows, every other curve and surface skipped by its
 * layout (OCCT's BinTools_CurveSet.cxx, BinTools_Curve2dSet.cxx and BinTools_SurfaceSet.cxx, the same in
 * OCCT 7.6-8.0). See cadedge/_shapedump.c for the whole shape. */
#include "_bintools.h"

enum { LINE = 0, CONIC = 1, SPLINE = 2, HYPERBOLA = 3, SKIPPED = -1 };
enum { BT_LINE = 1, BT_CIRCLE, BT_ELLIPSE, BT_PARABOLA, BT_HYPERBOLA, BT_BEZIER, BT_BSPLINE, BT_TRIMMED, BT_OFFSET };
enum { S_PLANE = 1, S_CYLINDER, S_CONE, S_SPHERE, S_TORUS, S_EXTRUSION, S_REVOLUTION, S_BEZIER, S_BSPLINE,
       S_RECTANGULAR, S_OFFSET };

int vec_reserve(Vec *v, Py_ssize_t extra)
{
    if (v->n + extra <= v->cap)
        return 0;
    Py_ssize_t cap = v->cap ? v->cap : 64;
    while (cap < v->n + extra)
        cap *= 2;
    double *d = realloc(v->d, cap * sizeof(double));
    if (!d)
        return -1;
    v->d = d, v->cap = cap;
    return 0;
}

int vec_push(Vec *v, const double *x, Py_ssize_t k)
{
    if (vec_reserve(v, k) < 0)
        return -1;
    memcpy(v->d + v->n, x, k * sizeof(double));
    v->n += k;
    return 0;
}


Py_ssize_t bt_header(Reader *r, const char *name)
{
    size_t len = strlen(name);
    if (r->pos + (Py_ssize_t)len + 2 > r->size || memcmp(r->d + r->pos, name, len) || r->d[r->pos + len] != ' ') {
        fail(r, "a section header is not where the layout puts it");
        return -1;
    }
    r->pos += len + 1;
    Py_ssize_t count = 0, digits = 0;
    while (r->pos < r->size && r->d[r->pos] >= '0' && r->d[r->pos] <= '9' && digits < 10)
        count = 10 * count + (r->d[r->pos++] - '0'), digits++;
    if (!digits || r->pos >= r->size || r->d[r->pos] != '\n') {
        fail(r, "a section header has no count");
        return -1;
    }
    r->pos++;
    if (count > r->size - r->pos) { /* every item takes at least a byte */
        fail(r, "a section counts more items than the stream holds");
        return -1;
    }
    return count;
}

/* A spline's poles, weights and knots: n poles of dim doubles (+ a weight if rational), nk (knot, mult). */
static int skip_spline(Reader *r, long n, long nk, int dim, int rational)
{
    if (n < 1 || nk < 0)
        return fail(r, "a spline has no poles");
    return skip(r, (Py_ssize_t)n * 8 * (dim + rational) + (Py_ssize_t)nk * 12);
}

/* A curve of dim (2 or 3) coordinates: the record is the same for both but for the sizes of its points and
   directions (a line: a point and a direction; a conic: a point, dim directions and its radii). */
static int skip_curve(Reader *r, int dim, int depth)
{
    int type = u8(r), rational;
    long degree;
    if (depth > MAX_DEPTH)
        return fail(r, "curves nested too deep");
    switch (type) {
    case BT_LINE: return skip(r, 2 * dim * 8);
    case BT_CIRCLE: case BT_PARABOLA: return skip(r, (dim + dim * dim + 1) * 8);
    case BT_ELLIPSE: case BT_HYPERBOLA: return skip(r, (dim + dim * dim + 2) * 8);
    case BT_BEZIER:
        rational = u8(r), degree = u16(r);
        return rational >= 0 && degree >= 0 && skip_spline(r, degree + 1, 0, dim, rational != 0);
    case BT_BSPLINE: {
        rational = u8(r), u8(r), degree = u16(r);
        long n = i32(r), nk = i32(r);
        return rational >= 0 && degree >= 0 && skip_spline(r, n, nk, dim, rational != 0);
    }
    case BT_TRIMMED: return skip(r, 2 * 8) && skip_curve(r, dim, depth + 1);
    case BT_OFFSET: return skip(r, (dim == 3 ? 4 : 1) * 8) && skip_curve(r, dim, depth + 1);  /* 3-D: a direction too */
    default: return fail(r, dim == 3 ? "a curve of unknown type" : "a 2-D curve of unknown type");
    }
}

int bt_skip_curve2d(Reader *r, int depth) { return skip_curve(r, 2, depth); }

int bt_skip_curve3d(Reader *r, int depth) { return skip_curve(r, 3, depth); }

int bt_skip_surface(Reader *r, int depth)
{
    int type = u8(r);
    if (depth > MAX_DEPTH)
        return fail(r, "surfaces nested too deep");
    switch (type) {
    case S_PLANE: return skip(r, 12 * 8);
    case S_CYLINDER: case S_SPHERE: return skip(r, 13 * 8);
    case S_CONE: case S_TORUS: return skip(r, 14 * 8);
    case S_EXTRUSION: return skip(r, 3 * 8) && bt_skip_curve3d(r, 0);
    case S_REVOLUTION: return skip(r, 6 * 8) && bt_skip_curve3d(r, 0);
    case S_BEZIER: {
        int ur = u8(r), vr = u8(r);
        long ud = u16(r), vd = u16(r);
        return ur >= 0 && vr >= 0 && ud >= 0 && vd >= 0 && skip_spline(r, (ud + 1) * (vd + 1), 0, 3, ur || vr);
    }
    case S_BSPLINE: {
        int ur = u8(r), vr = u8(r);
        u8(r), u8(r);
        long ud = u16(r), vd = u16(r), nu = i32(r), nv = i32(r), nku = i32(r), nkv = i32(r);
        return ur >= 0 && vr >= 0 && ud >= 0 && vd >= 0 && nu > 0 && nv > 0 &&
               skip_spline(r, nu * nv, nku + nkv, 3, ur || vr);
    }
    case S_RECTANGULAR: return skip(r, 4 * 8) && bt_skip_surface(r, depth + 1);
    case S_OFFSET: return skip(r, 8) && bt_skip_surface(r, depth + 1);
    default: return fail(r, "a surface of unknown type");
    }
}

/* One curve as a geometry table row (cadedge/_batch.c): meta = (kind, degree, knots, dim, periodic, type);
 * kind SKIPPED for the types the table does not evaluate (parabola, trimmed, offset). */
static int parse_curve(Reader *r, int64_t *m, Vec *out)
{
    Py_ssize_t at = r->pos;
    int type = u8(r);
    m[5] = type;
    if (type == BT_LINE) {
        double v[6];
        if (!need(r, 48))
            return 0;
        for (int k = 0; k < 6; k++)
            v[k] = f64(r);
        m[0] = LINE;
        return vec_push(out, v, 6) < 0 ? -1 : 1;
    }
    if (type == BT_CIRCLE || type == BT_ELLIPSE || type == BT_HYPERBOLA) { /* (a hyperbola as an ellipse) */
        int radii = type == BT_CIRCLE ? 1 : 2;
        double v[11]; /* location, (axis skipped), X direction, Y direction, radii */
        if (!need(r, 96 + 8 * radii))
            return 0;
        const unsigned char *p = r->d + r->pos;
        for (int k = 0; k < 3; k++)
            v[k] = le_double(p + 8 * k);
        for (int k = 3; k < 9; k++)
            v[k] = le_double(p + 8 * (k + 3));
        v[9] = le_double(p + 96);
        v[10] = radii == 2 ? le_double(p + 104) : v[9];
        r->pos += 96 + 8 * radii;
        m[0] = type == BT_HYPERBOLA ? HYPERBOLA : CONIC;
        return vec_push(out, v, 11) < 0 ? -1 : 1;
    }
    if (type == BT_BEZIER || type == BT_BSPLINE) {
        int spline = type == BT_BSPLINE;
        int rational = u8(r) > 0;
        m[4] = spline ? u8(r) > 0 : 0;
        long degree = u16(r);
        long n = degree + 1, nk = 0;
        if (spline)
            n = i32(r), nk = i32(r);
        if (r->error || degree < 0 || n < 1 || nk < 0)
            return fail(r, "a spline has no poles");
        Py_ssize_t dim = rational ? 4 : 3;
        if (!need(r, (Py_ssize_t)n * 8 * dim + (Py_ssize_t)nk * 12))
            return 0;
        const unsigned char *p = r->d + r->pos;
        double nan = NAN;
        if (vec_push(out, &nan, 1) < 0)
            return -1;
        Py_ssize_t knots = 0;
        if (spline) {
            const unsigned char *kp = p + n * 8 * dim;
            for (Py_ssize_t k = 0; k < nk; k++) {
                double knot = le_double(kp + 12 * k);
                int32_t mult = (int32_t)le(kp + 12 * k + 8, 4);
                if (mult < 0 || knots + mult > n + degree + 1) /* at most poles + degree + 1 in all */
                    return fail(r, "a spline's knot multiplicities exceed its poles");
                for (int32_t j = 0; j < mult; j++)
                    if (vec_push(out, &knot, 1) < 0)
                        return -1;
                knots += mult;
            }
        } else {
            double ends[2] = {0.0, 1.0};
            for (int e = 0; e < 2; e++)
                for (long j = 0; j <= degree; j++)
                    if (vec_push(out, ends + e, 1) < 0)
                        return -1;
            knots = 2 * (degree + 1);
        }
        for (Py_ssize_t i = 0; i < n; i++) {
            double v[4];
            for (int k = 0; k < dim; k++)
                v[k] = le_double(p + 8 * (dim * i + k));
            if (rational)
                v[0] *= v[3], v[1] *= v[3], v[2] *= v[3];
            if (vec_push(out, v, dim) < 0)
                return -1;
        }
        r->pos += n * 8 * dim + nk * 12;
        m[0] = SPLINE, m[1] = degree, m[2] = knots, m[3] = dim;
        return 1;
    }
    r->pos = at;
    m[0] = SKIPPED;
    return bt_skip_curve3d(r, 0);
}

int bt_parse_curves_at(Reader *r, Py_ssize_t count, int64_t *meta, int64_t *offsets, Vec *out)
{
    offsets[0] = 0;
    for (Py_ssize_t c = 0; c < count; c++) {
        int ok = parse_curve(r, meta + 6 * c, out);
        if (ok <= 0)
            return ok;
        offsets[c + 1] = out->n;
    }
    return 1;
}

PyObject *bt_refused(Reader *r, const char *where)
{
    PyErr_Format(PyExc_ValueError, "%s: %s (at byte %zd)", where, r->error ? r->error : "refused", r->pos);
    return NULL;
}

/* parse_curves(data, start, count) -> (meta, offsets, numbers, end): the count curves that
 * BinTools_CurveSet::Write put in data from byte start, as geometry table rows (bytearrays of int64,
 * int64, float64; see parse_curve), and the byte after them. */
PyObject *ck_parse_curves(PyObject *self, PyObject *args)
{
    Py_buffer buf;
    Py_ssize_t start, count;
    if (!PyArg_ParseTuple(args, "y*nn", &buf, &start, &count))
        return NULL;
    Reader r = {buf.buf, buf.len, start, NULL};
    PyObject *result = NULL;
    int64_t *meta = calloc(6 * count + 1, sizeof(int64_t)), *offsets = calloc(count + 1, sizeof(int64_t));
    Vec out = {0};
    int ok = meta && offsets && start >= 0 ? bt_parse_curves_at(&r, count, meta, offsets, &out) : -1;
    if (ok < 0)
        PyErr_NoMemory();
    else if (ok == 0)
        bt_refused(&r, "parse_curves");
    else
        result = Py_BuildValue("(NNNn)", as_bytes(meta, 6 * count * 8), as_bytes(offsets, (count + 1) * 8),
                               as_bytes(out.d, out.n * 8), r.pos);
    free(meta), free(offsets), free(out.d);
    PyBuffer_Release(&buf);
    return result;
}

