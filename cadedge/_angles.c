/* Triangle angles for the surface mesh's face optimiser (cadedge/mesh/moves.py, optimize.py): the smallest
 * interior angle of many triangles, and of each node's triangles with the node moved to a trial position;
 * and triangle normals, which its fold and flip checks take as often (numpy's gather and cross product
 * were 11 of the 54 s it spent on the M6 screw at ALD 1e-3).
 *
 * The optimiser asks these thousands of times per face on a few thousand triangles each (24 trial positions
 * per node and iteration in the local search), where numpy spent most of its time gathering corners and
 * grouping by node: 12 of the 19 s cadedge mesh took on the bracket fixture at ALD 1e-3. An angle is
 * numpy's formula operation by operation (quality.triangle_angles: atan2(|e0 x e1|, -e_k . e_k-1), in
 * degrees) at the corner opposite the shortest edge.
 */
#include "_kernels.h"

#define DEGREES 57.29577951308232 /* 180 / pi */

/* The smallest angle (degrees) of the triangle a, b, c (3-vectors): the one opposite the shortest edge (one
 * atan2 instead of three; where two edges tie, either corner's angle, equal up to rounding). */
static double min_angle(const double *a, const double *b, const double *c)
{
    const double *p[3] = {a, b, c};
    double e[3][3], sq[3];
    for (int k = 0; k < 3; k++) {
        for (int d = 0; d < 3; d++)
            e[k][d] = p[(k + 1) % 3][d] - p[k][d]; /* edge k leaves corner k */
        sq[k] = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
    }
    int shortest = sq[1] < sq[0] ? 1 : 0;
    if (sq[2] < sq[shortest])
        shortest = 2;
    int k = (shortest + 2) % 3; /* the corner opposite edge `shortest` */
    double cx = e[0][1] * e[1][2] - e[0][2] * e[1][1];
    double cy = e[0][2] * e[1][0] - e[0][0] * e[1][2];
    double cz = e[0][0] * e[1][1] - e[0][1] * e[1][0];
    const double *f = e[k], *g = e[(k + 2) % 3];
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), -(f[0] * g[0] + f[1] * g[1] + f[2] * g[2])) * DEGREES;
}

/* Whether every index of tri (count entries) is a node below n; if not, an IndexError is set. */
static int nodes_in_range(const int64_t *tri, Py_ssize_t count, Py_ssize_t n, const char *name)
{
    for (Py_ssize_t i = 0; i < count; i++)
        if (tri[i] < 0 || tri[i] >= n) {
            PyErr_Format(PyExc_IndexError, "%s: node index out of range", name);
            return 0;
        }
    return 1;
}

/* The arguments (x (n, 3) f64, tri (m, 3) i64, out (m, per) f64, writable) of a per-triangle kernel, taken
 * into b and checked: shapes and node indices. Returns m, or -1 with an exception set (b released). */
static Py_ssize_t triangle_args(Buffers *b, PyObject *args, Py_ssize_t per, const char *name, const double **x,
                                const int64_t **tri, double **out)
{
    Py_ssize_t nx, nt, nout;
    *x = ck_arg(b, args, 0, F64, 0, &nx);
    *tri = ck_arg(b, args, 1, I64, 0, &nt);
    *out = ck_arg(b, args, 2, F64, 1, &nout);
    if (!*out) {
        ck_release(b);
        return -1;
    }
    if (nx % 3 || nt % 3 || nout != nt / 3 * per) {
        ck_release(b);
        PyErr_Format(PyExc_ValueError, "%s: mismatched shapes", name);
        return -1;
    }
    if (!nodes_in_range(*tri, nt, nx / 3, name)) {
        ck_release(b);
        return -1;
    }
    return nt / 3;
}

/* min_angles(x (n, 3) f64, tri (m, 3) i64, out (m,) f64): the smallest angle of each triangle. */
PyObject *ck_min_angles(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    const double *x;
    const int64_t *tri;
    double *out;
    Py_ssize_t m = triangle_args(&b, args, 1, "min_angles", &x, &tri, &out);
    if (m < 0)
        return NULL;
    for (Py_ssize_t t = 0; t < m; t++)
        out[t] = min_angle(x + 3 * tri[3 * t], x + 3 * tri[3 * t + 1], x + 3 * tri[3 * t + 2]);
    ck_release(&b);
    Py_RETURN_NONE;
}

/* climb_trials(x (n, 3) f64, tri (m, 3) i64, node (q,) i64, slot (q,) i64, t (q,) i64, u (n, 3) f64,
 * v (n, 3) f64, h (n,) f64, steps (s,) f64, cosines (a,) f64, sines (a,) f64, best (n,) f64, best_pos (n, 3)
 * f64): the local search's trials (cadedge.mesh.moves.climb_nodes) in one call. For each step and then
 * each direction, every node of the incidences is tried at x + (step h) (cos u + sin v), its smallest
 * angle there that of its worst triangle; where that beats best by more than 1e-9, best and best_pos get it
 * (both read and written). The sums and products in numpy's order, so the same results as one numpy
 * expression and kernel call per trial, which cost 5 s of the optimiser's 20 s on an 18-solid assembly
 * (96 000 calls). */
PyObject *ck_climb_trials(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t nx, nt, nn, ns, ntt, nu, nv, nh, nsteps, nc, nsn, nbest, npos;
    const double *x = ck_arg(&b, args, 0, F64, 0, &nx);
    const int64_t *tri = ck_arg(&b, args, 1, I64, 0, &nt);
    const int64_t *node = ck_arg(&b, args, 2, I64, 0, &nn);
    const int64_t *slot = ck_arg(&b, args, 3, I64, 0, &ns);
    const int64_t *t = ck_arg(&b, args, 4, I64, 0, &ntt);
    const double *u = ck_arg(&b, args, 5, F64, 0, &nu);
    const double *v = ck_arg(&b, args, 6, F64, 0, &nv);
    const double *h = ck_arg(&b, args, 7, F64, 0, &nh);
    const double *steps = ck_arg(&b, args, 8, F64, 0, &nsteps);
    const double *cosines = ck_arg(&b, args, 9, F64, 0, &nc);
    const double *sines = ck_arg(&b, args, 10, F64, 0, &nsn);
    double *best = ck_arg(&b, args, 11, F64, 1, &nbest);
    double *best_pos = ck_arg(&b, args, 12, F64, 1, &npos);
    if (!best_pos) {
        ck_release(&b);
        return NULL;
    }
    Py_ssize_t n = nx / 3, m = nt / 3;
    if (nx % 3 || nt % 3 || ns != nn || ntt != nn || nu != nx || nv != nx || nh != n || nsn != nc || nbest != n
        || npos != nx) {
        ck_release(&b);
        PyErr_SetString(PyExc_ValueError, "climb_trials: mismatched shapes");
        return NULL;
    }
    if (!nodes_in_range(tri, nt, n, "climb_trials")) {
        ck_release(&b);
        return NULL;
    }
    for (Py_ssize_t i = 0; i < nn; i++)
        if (node[i] < 0 || node[i] >= n || slot[i] < 0 || slot[i] > 2 || t[i] < 0 || t[i] >= m) {
            ck_release(&b);
            PyErr_SetString(PyExc_IndexError, "climb_trials: incidence out of range");
            return NULL;
        }
    double *q = PyMem_Malloc((size_t)(4 * n + 1) * sizeof(double)); /* each node's worst, then its trial */
    if (!q) {
        ck_release(&b);
        return PyErr_NoMemory();
    }
    double *pos = q + n;
    for (Py_ssize_t s = 0; s < nsteps; s++)
        for (Py_ssize_t a = 0; a < nc; a++) {
            for (Py_ssize_t i = 0; i < n; i++)
                q[i] = INFINITY;
            for (Py_ssize_t i = 0; i < nn; i++) {
                Py_ssize_t j = node[i];
                if (q[j] == INFINITY) /* its trial position, once per node */
                    for (int d = 0; d < 3; d++)
                        pos[3 * j + d] = x[3 * j + d]
                                         + steps[s] * h[j] * (cosines[a] * u[3 * j + d] + sines[a] * v[3 * j + d]);
                const double *p[3];
                for (int k = 0; k < 3; k++)
                    p[k] = x + 3 * tri[3 * t[i] + k];
                p[slot[i]] = pos + 3 * j;
                double angle = min_angle(p[0], p[1], p[2]);
                if (angle < q[j] || angle != angle)
                    q[j] = angle;
            }
            for (Py_ssize_t i = 0; i < nn; i++) {
                Py_ssize_t j = node[i];
                if (q[j] != INFINITY && q[j] > best[j] + 1e-9) {
                    best[j] = q[j];
                    for (int d = 0; d < 3; d++)
                        best_pos[3 * j + d] = pos[3 * j + d];
                }
            }
        }
    PyMem_Free(q);
    ck_release(&b);
    Py_RETURN_NONE;
}

/* tri_normals(x (n, 3) f64, tri (m, 3) i64, out (m, 3) f64): each triangle's (b - a) x (c - a), twice its
 * area in length: numpy's formula (cadedge.mesh.folds), operation by operation. */
PyObject *ck_tri_normals(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    const double *x;
    const int64_t *tri;
    double *out;
    Py_ssize_t m = triangle_args(&b, args, 3, "tri_normals", &x, &tri, &out);
    if (m < 0)
        return NULL;
    for (Py_ssize_t t = 0; t < m; t++) {
        const double *a = x + 3 * tri[3 * t], *p = x + 3 * tri[3 * t + 1], *q = x + 3 * tri[3 * t + 2];
        double u[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]}, v[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
        out[3 * t] = u[1] * v[2] - u[2] * v[1];
        out[3 * t + 1] = u[2] * v[0] - u[0] * v[2];
        out[3 * t + 2] = u[0] * v[1] - u[1] * v[0];
    }
    ck_release(&b);
    Py_RETURN_NONE;
}
