/* The contact kernels of tapecoil.contact: closest points on biquadratic (9-node) cells, the
 * nodal normals of a Q2 surface and their derivatives, a node-to-surface pair's gap along the
 * smoothed normal with its exact derivatives, and the pairs' dependence on the nodal normals
 * applied to a vector. The formulas are stated in tapecoil/contact/linearisation.py and
 * projection.py; this file computes them pair by pair instead of in numpy arrays of all pairs.
 *
 * Arrays are C-contiguous doubles (int64 for indices). A surface is given by node positions
 * x (N, 3) and cells (Nc, 9) of node indices in basix's Q2 order (the tensor indices QI, QJ). */
#include <math.h>
#include <stdint.h>
#include <string.h>

static const int QI[9] = {0, 2, 0, 2, 1, 0, 2, 1, 1};
static const int QJ[9] = {0, 0, 2, 2, 0, 1, 1, 2, 1};

static void lagrange2(double t, double l[3], double d[3])
{
  l[0] = 2.0 * (t - 0.5) * (t - 1.0);
  l[1] = -4.0 * t * (t - 1.0);
  l[2] = 2.0 * t * (t - 0.5);
  d[0] = 4.0 * t - 3.0;
  d[1] = 4.0 - 8.0 * t;
  d[2] = 4.0 * t - 1.0;
}

/* shape functions N[9] and reference gradients dN[9][2] at r */
static void q2_basis(const double r[2], double N[9], double dN[9][2])
{
  double lx[3], dx[3], ly[3], dy[3];
  lagrange2(r[0], lx, dx);
  lagrange2(r[1], ly, dy);
  for (int b = 0; b < 9; ++b)
  {
    N[b] = lx[QI[b]] * ly[QJ[b]];
    dN[b][0] = dx[QI[b]] * ly[QJ[b]];
    dN[b][1] = lx[QI[b]] * dy[QJ[b]];
  }
}

/* second reference derivatives H[9][2][2] at r */
static void q2_second(const double r[2], double H[9][2][2])
{
  static const double s[3] = {4.0, -8.0, 4.0};
  double lx[3], dx[3], ly[3], dy[3];
  lagrange2(r[0], lx, dx);
  lagrange2(r[1], ly, dy);
  for (int b = 0; b < 9; ++b)
  {
    H[b][0][0] = s[QI[b]] * ly[QJ[b]];
    H[b][1][1] = lx[QI[b]] * s[QJ[b]];
    H[b][0][1] = H[b][1][0] = dx[QI[b]] * dy[QJ[b]];
  }
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3(const double a[3], const double b[3], double c[3])
{
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* the cell's nodes X[9][3] from x and a row of cells */
static void gather_cell(const double* x, const int64_t* row, double X[9][3])
{
  for (int b = 0; b < 9; ++b)
    for (int i = 0; i < 3; ++i)
      X[b][i] = x[3 * row[b] + i];
}

/* y = N_b X_b and the tangents t_j = dN_b/dr_j X_b */
static void surface_point(const double N[9], const double dN[9][2], const double X[9][3], double y[3],
                          double t[2][3])
{
  for (int i = 0; i < 3; ++i)
  {
    y[i] = t[0][i] = t[1][i] = 0.0;
    for (int b = 0; b < 9; ++b)
    {
      y[i] += N[b] * X[b][i];
      t[0][i] += dN[b][0] * X[b][i];
      t[1][i] += dN[b][1] * X[b][i];
    }
  }
}

/* whether each coordinate is held on an edge: at the edge with the descent pointing out */
static void held_coordinates(const double ref[2], const double rhs[2], int held[2])
{
  for (int j = 0; j < 2; ++j)
    held[j] = (ref[j] <= 0.0 && rhs[j] < 0.0) || (ref[j] >= 1.0 && rhs[j] > 0.0);
}

/* Closest points: for each of n queries, the point of cell cell[k] closest to node[k] (both
 * indices into x and cells), by Gauss-Newton on |x - y(r)|^2 with a coordinate that would leave
 * the square held on its edge (projection.py's closest_points). start (n, 2) or NULL (the cell
 * centres). Outputs (each may be NULL): ref (n, 2), held (n, 2) as 0/1, N (n, 9), y (n, 3), the
 * cell's unit normal (n, 3), distance (n), unit direction from y to the point (n, 3); with
 * nodal (N, 3) given: the smoothed unit normal m/|m|, m = N_b n_b (n, 3), the distance along it
 * (n) and beside it (n). */
void tc_closest_points(int64_t n, const int64_t* node, const int64_t* cell, const double* x,
                       const int64_t* cells, const double* start, int iterations, const double* nodal,
                       double* ref_out, int8_t* held_out, double* N_out, double* y_out,
                       double* normal_out, double* distance_out, double* direction_out,
                       double* smooth_out, double* along_out, double* beside_out)
{
  for (int64_t k = 0; k < n; ++k)
  {
    double X[9][3], N[9], dN[9][2], y[3], t[2][3], ref[2], rhs[2], r[3];
    int held[2];
    const int64_t* row = cells + 9 * cell[k];
    const double* p = x + 3 * node[k];
    gather_cell(x, row, X);
    ref[0] = start ? start[2 * k] : 0.5;
    ref[1] = start ? start[2 * k + 1] : 0.5;
    for (int it = 0; it < iterations; ++it)
    {
      q2_basis(ref, N, dN);
      surface_point(N, dN, X, y, t);
      for (int i = 0; i < 3; ++i)
        r[i] = p[i] - y[i];
      rhs[0] = dot3(t[0], r);
      rhs[1] = dot3(t[1], r);
      held_coordinates(ref, rhs, held);
      double G[2][2] = {{dot3(t[0], t[0]), dot3(t[0], t[1])}, {dot3(t[1], t[0]), dot3(t[1], t[1])}};
      for (int j = 0; j < 2; ++j)
        for (int l = 0; l < 2; ++l)
          if (held[j] || held[l])
            G[j][l] = (j == l) ? 1.0 : 0.0;
      double b0 = held[0] ? 0.0 : rhs[0], b1 = held[1] ? 0.0 : rhs[1];
      double det = G[0][0] * G[1][1] - G[0][1] * G[1][0];
      if (det == 0.0)
        break;
      double s0 = (G[1][1] * b0 - G[0][1] * b1) / det;
      double s1 = (G[0][0] * b1 - G[1][0] * b0) / det;
      ref[0] = fmin(fmax(ref[0] + s0, 0.0), 1.0);
      ref[1] = fmin(fmax(ref[1] + s1, 0.0), 1.0);
    }
    q2_basis(ref, N, dN);
    surface_point(N, dN, X, y, t);
    for (int i = 0; i < 3; ++i)
      r[i] = p[i] - y[i];
    rhs[0] = dot3(t[0], r);
    rhs[1] = dot3(t[1], r);
    held_coordinates(ref, rhs, held);
    double distance = sqrt(dot3(r, r));
    if (ref_out)
    {
      ref_out[2 * k] = ref[0];
      ref_out[2 * k + 1] = ref[1];
    }
    if (held_out)
    {
      held_out[2 * k] = (int8_t)held[0];
      held_out[2 * k + 1] = (int8_t)held[1];
    }
    if (N_out)
      memcpy(N_out + 9 * k, N, 9 * sizeof(double));
    if (y_out)
      memcpy(y_out + 3 * k, y, 3 * sizeof(double));
    if (normal_out)
    {
      double c[3];
      cross3(t[0], t[1], c);
      double length = sqrt(dot3(c, c));
      for (int i = 0; i < 3; ++i)
        normal_out[3 * k + i] = c[i] / length;
    }
    if (distance_out)
      distance_out[k] = distance;
    if (direction_out)
    {
      double scale = distance > 1e-300 ? distance : 1e-300;
      for (int i = 0; i < 3; ++i)
        direction_out[3 * k + i] = r[i] / scale;
    }
    if (nodal)
    {
      double m[3] = {0.0, 0.0, 0.0};
      for (int b = 0; b < 9; ++b)
        for (int i = 0; i < 3; ++i)
          m[i] += N[b] * nodal[3 * row[b] + i];
      double length = sqrt(dot3(m, m));
      for (int i = 0; i < 3; ++i)
        m[i] /= length;
      double along = dot3(r, m), off[3];
      for (int i = 0; i < 3; ++i)
        off[i] = r[i] - along * m[i];
      if (smooth_out)
        memcpy(smooth_out + 3 * k, m, 3 * sizeof(double));
      if (along_out)
        along_out[k] = along;
      if (beside_out)
        beside_out[k] = sqrt(dot3(off, off));
    }
  }
}

/* the reference gradients of the shape functions at the 9 nodes: G[b][a][j] = dN_a/dr_j at
 * node b's reference point (QI[b] / 2, QJ[b] / 2) */
static void node_gradients(double G[9][9][2])
{
  for (int b = 0; b < 9; ++b)
  {
    double r[2] = {0.5 * QI[b], 0.5 * QJ[b]}, N[9], dN[9][2];
    q2_basis(r, N, dN);
    for (int a = 0; a < 9; ++a)
    {
      G[b][a][0] = dN[a][0];
      G[b][a][1] = dN[a][1];
    }
  }
}

/* Nodal normals: each node's unit normal is the normalised sum of the unit normals
 * nu = t_1 x t_2 / |t_1 x t_2| of the cells around it at the node. Outputs: normals (N, 3), the
 * sums' lengths (N); per cell and node, the tangents t (Nc, 9, 2, 3), nu (Nc, 9, 3) and
 * |t_1 x t_2| (Nc, 9), which the derivatives take. */
void tc_nodal_normals(int64_t n_cells, const int64_t* cells, int64_t n_nodes, const double* x,
                      double* normals, double* length, double* t_out, double* nu_out, double* T_length)
{
  double G[9][9][2];
  node_gradients(G);
  memset(normals, 0, 3 * n_nodes * sizeof(double));
  for (int64_t c = 0; c < n_cells; ++c)
  {
    double X[9][3];
    const int64_t* row = cells + 9 * c;
    gather_cell(x, row, X);
    for (int b = 0; b < 9; ++b)
    {
      double t[2][3] = {{0, 0, 0}, {0, 0, 0}}, T[3];
      for (int a = 0; a < 9; ++a)
        for (int i = 0; i < 3; ++i)
        {
          t[0][i] += G[b][a][0] * X[a][i];
          t[1][i] += G[b][a][1] * X[a][i];
        }
      cross3(t[0], t[1], T);
      double L = sqrt(dot3(T, T));
      double* tt = t_out + (9 * c + b) * 6;
      for (int i = 0; i < 3; ++i)
      {
        tt[i] = t[0][i];
        tt[3 + i] = t[1][i];
        nu_out[(9 * c + b) * 3 + i] = T[i] / L;
        normals[3 * row[b] + i] += T[i] / L;
      }
      T_length[9 * c + b] = L;
    }
  }
  for (int64_t k = 0; k < n_nodes; ++k)
  {
    double* v = normals + 3 * k;
    double L = sqrt(dot3(v, v));
    length[k] = L;
    double s = L > 1e-300 ? L : 1e-300;
    for (int i = 0; i < 3; ++i)
      v[i] /= s;
  }
}

/* (I - n n^T) / length: the derivative of v/|v| at v = length n */
static void projector(const double n[3], double length, double P[3][3])
{
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      P[i][j] = ((i == j) - n[i] * n[j]) / length;
}

static void matmul3(const double A[3][3], const double B[3][3], double C[3][3])
{
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      C[i][j] = A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j];
}

/* [v]_x: [v]_x w = v x w */
static void cross_matrix(const double v[3], double M[3][3])
{
  M[0][0] = M[1][1] = M[2][2] = 0.0;
  M[0][1] = -v[2];
  M[0][2] = v[1];
  M[1][0] = v[2];
  M[1][2] = -v[0];
  M[2][0] = -v[1];
  M[2][1] = v[0];
}

/* The nodal normals' derivatives: D[slot] (3, 3) = dn_k/dX_j for every node k and node j of the
 * cells around k, summed into the slot slots[(9 c + b) 9 + a] of node k = cells[c][b] and
 * j = cells[c][a] (the caller's numbering of each node's neighbourhood). From tc_nodal_normals'
 * outputs. D (n_slots, 3, 3) is overwritten. */
void tc_normal_derivatives(int64_t n_cells, const int64_t* cells, const int64_t* slots, int64_t n_slots,
                           const double* normals, const double* length, const double* t,
                           const double* nu, const double* T_length, double* D)
{
  double G[9][9][2];
  node_gradients(G);
  memset(D, 0, 9 * n_slots * sizeof(double));
  for (int64_t c = 0; c < n_cells; ++c)
    for (int b = 0; b < 9; ++b)
    {
      int64_t k = cells[9 * c + b];
      double outer[3][3], inner[3][3], M[3][3], T1[3][3], T0[3][3];
      projector(normals + 3 * k, length[k], outer);
      projector(nu + (9 * c + b) * 3, T_length[9 * c + b], inner);
      matmul3(outer, inner, M);
      const double* tt = t + (9 * c + b) * 6;
      cross_matrix(tt + 3, T1);
      cross_matrix(tt, T0);
      for (int a = 0; a < 9; ++a)
      {
        /* dT/dX_a = -dN_a/dr_1 [t_2]_x + dN_a/dr_2 [t_1]_x, T = t_1 x t_2 */
        double dT[3][3], block[3][3];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            dT[i][j] = -G[b][a][0] * T1[i][j] + G[b][a][1] * T0[i][j];
        matmul3(M, dT, block);
        double* out = D + 9 * slots[(9 * c + b) * 9 + a];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            out[3 * i + j] += block[i][j];
      }
    }
}

/* solve the 2 x 2 system H z = l for each of ncol right-hand sides l (L[2][ncol]) */
static void solve2(const double H[2][2], const double* L0, const double* L1, int ncol, double* z0,
                   double* z1)
{
  double det = H[0][0] * H[1][1] - H[0][1] * H[1][0];
  for (int a = 0; a < ncol; ++a)
  {
    z0[a] = (H[1][1] * L0[a] - H[0][1] * L1[a]) / det;
    z1[a] = (H[0][0] * L1[a] - H[1][0] * L0[a]) / det;
  }
}

/* A pair's force direction and, with the matrix outputs given, its exact derivative at fixed
 * nodal normals (linearisation.py's gap_derivatives): for each of P pairs, contact node node[p]
 * against cell cell[p] at the closest point ref[p] (held coordinates held[p]), on side side[p].
 * B (P, 30): the force's direction on (x, X_1..X_9), side n_s (x) (1, -N_1, ..., -N_9). With
 * matrix (P, 30, 30) and sensitivity (P, 30, 3) given: the force f B differentiated,
 * stiffness B (x) dg + force dB, and with respect to m = N_b n_b, stiffness B (x) dg/dm +
 * force dB/dm, for the pairs' force (P) and stiffness (P) = d2E/dg2. */
void tc_pair_blocks(int64_t P, const int64_t* node, const int64_t* cell, const double* x,
                    const int64_t* cells, const double* nodal, const double* ref_in, const int8_t* held_in,
                    const double* side_in, const double* force, const double* stiffness, double* B_out,
                    double* matrix, double* sensitivity)
{
  for (int64_t p = 0; p < P; ++p)
  {
    const int64_t* row = cells + 9 * cell[p];
    const double* xp = x + 3 * node[p];
    const double side = side_in[p];
    double X[9][3], nod[9][3], N[9], dN[9][2], H2[9][2][2];
    const double ref[2] = {ref_in[2 * p], ref_in[2 * p + 1]};
    const int held[2] = {held_in[2 * p], held_in[2 * p + 1]};
    gather_cell(x, row, X);
    gather_cell(nodal, row, nod);
    q2_basis(ref, N, dN);
    double y[3], tang[2][3], r[3], m[3] = {0, 0, 0}, dm[2][3] = {{0, 0, 0}, {0, 0, 0}};
    surface_point(N, dN, X, y, tang);
    for (int i = 0; i < 3; ++i)
    {
      r[i] = xp[i] - y[i];
      for (int b = 0; b < 9; ++b)
      {
        m[i] += N[b] * nod[b][i];
        dm[0][i] += dN[b][0] * nod[b][i];
        dm[1][i] += dN[b][1] * nod[b][i];
      }
    }
    double length = sqrt(dot3(m, m)), n[3], e[3], shape[10];
    for (int i = 0; i < 3; ++i)
    {
      n[i] = m[i] / length;
      e[i] = side * n[i];
    }
    shape[0] = 1.0;
    for (int b = 0; b < 9; ++b)
      shape[b + 1] = -N[b];
    double* B = B_out + 30 * p;
    for (int a = 0; a < 10; ++a)
      for (int i = 0; i < 3; ++i)
        B[3 * a + i] = shape[a] * e[i];
    if (!matrix)
      continue;

    double turn[3][3], dn[2][3];
    projector(n, length, turn);
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i)
        dn[j][i] = turn[i][0] * dm[j][0] + turn[i][1] * dm[j][1] + turn[i][2] * dm[j][2];
    q2_second(ref, H2);
    double second[2][2][3];
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 3; ++i)
        {
          second[j][k][i] = 0.0;
          for (int b = 0; b < 9; ++b)
            second[j][k][i] += H2[b][j][k] * X[b][i];
        }
    double H[2][2], L[2][30];
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        H[j][k] = dot3(tang[j], tang[k]) - dot3(r, second[j][k]);
    for (int j = 0; j < 2; ++j)
    {
      for (int a = 0; a < 10; ++a)
        for (int i = 0; i < 3; ++i)
          L[j][3 * a + i] = shape[a] * tang[j][i] + (a > 0 ? dN[a - 1][j] * r[i] : 0.0);
    }
    for (int j = 0; j < 2; ++j)
      if (held[j])
      {
        for (int a = 0; a < 30; ++a)
          L[j][a] = 0.0;
        for (int k = 0; k < 2; ++k)
          H[j][k] = H[k][j] = 0.0;
      }
    for (int j = 0; j < 2; ++j)
      if (held[j])
        H[j][j] = 1.0;
    double dr[2][30];
    solve2(H, L[0], L[1], 30, dr[0], dr[1]);

    double c[2], dg[30];
    for (int j = 0; j < 2; ++j)
      c[j] = side * (dot3(r, dn[j]) - dot3(tang[j], n));
    for (int a = 0; a < 30; ++a)
      dg[a] = B[a] + c[0] * dr[0][a] + c[1] * dr[1][a];
    double dB_dr[2][30];
    for (int j = 0; j < 2; ++j)
    {
      for (int i = 0; i < 3; ++i)
        dB_dr[j][i] = side * dn[j][i];
      for (int b = 0; b < 9; ++b)
        for (int i = 0; i < 3; ++i)
          dB_dr[j][3 * (b + 1) + i] = -N[b] * side * dn[j][i] - dN[b][j] * e[i];
    }
    double* M = matrix + 900 * p;
    const double f = force[p], s = stiffness[p];
    for (int a = 0; a < 30; ++a)
      for (int b = 0; b < 30; ++b)
        M[30 * a + b] = s * B[a] * dg[b] + f * (dB_dr[0][a] * dr[0][b] + dB_dr[1][a] * dr[1][b]);
    double dg_dm[3];
    for (int k = 0; k < 3; ++k)
      dg_dm[k] = side * (r[0] * turn[0][k] + r[1] * turn[1][k] + r[2] * turn[2][k]);
    double* S = sensitivity + 90 * p;
    for (int a = 0; a < 10; ++a)
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
          S[3 * (3 * a + i) + k] = s * B[3 * a + i] * dg_dm[k] + f * side * shape[a] * turn[i][k];
  }
}

/* The pairs' dependence on the nodal normals applied to a vector (term.py's apply_coupling):
 * with v (N, 3) the vector's values at the surface's nodes, w_k = sum_j D_kj v_j (the nodal
 * normals' change) for every node k (neighbourhoods: slot_start (N + 1), slot_node (n_slots)),
 * and for each pair out[p] (30) = S_p (sum_b N_pb w_{cells[cell_p][b]}). transpose: from the
 * pair values v_rows (P, 30), z_k = sum over pairs and partner nodes b = k of N_pb S_p^T v_p,
 * then out_nodes[j] += sum_k D_kj^T z_k (out_nodes (N, 3), overwritten). work (N, 3) is scratch. */
void tc_apply_normals(int64_t P, const int64_t* cell, const int64_t* cells, const double* N_in,
                      const double* S_in, int64_t n_nodes, const int64_t* slot_start, const int64_t* slot_node,
                      const double* D, int transpose, const double* v, double* work, double* out)
{
  if (!transpose)
  {
    for (int64_t k = 0; k < n_nodes; ++k)
    {
      double w[3] = {0, 0, 0};
      for (int64_t s = slot_start[k]; s < slot_start[k + 1]; ++s)
      {
        const double* Dk = D + 9 * s;
        const double* vj = v + 3 * slot_node[s];
        for (int i = 0; i < 3; ++i)
          w[i] += Dk[3 * i] * vj[0] + Dk[3 * i + 1] * vj[1] + Dk[3 * i + 2] * vj[2];
      }
      memcpy(work + 3 * k, w, 3 * sizeof(double));
    }
    for (int64_t p = 0; p < P; ++p)
    {
      const int64_t* row = cells + 9 * cell[p];
      const double* Np = N_in + 9 * p;
      double change[3] = {0, 0, 0};
      for (int b = 0; b < 9; ++b)
        for (int i = 0; i < 3; ++i)
          change[i] += Np[b] * work[3 * row[b] + i];
      const double* S = S_in + 90 * p;
      for (int a = 0; a < 30; ++a)
        out[30 * p + a] = S[3 * a] * change[0] + S[3 * a + 1] * change[1] + S[3 * a + 2] * change[2];
    }
    return;
  }
  memset(work, 0, 3 * n_nodes * sizeof(double));
  for (int64_t p = 0; p < P; ++p)
  {
    const int64_t* row = cells + 9 * cell[p];
    const double* Np = N_in + 9 * p;
    const double* S = S_in + 90 * p;
    const double* vp = v + 30 * p;
    double z[3] = {0, 0, 0};
    for (int a = 0; a < 30; ++a)
      for (int k = 0; k < 3; ++k)
        z[k] += S[3 * a + k] * vp[a];
    for (int b = 0; b < 9; ++b)
      for (int k = 0; k < 3; ++k)
        work[3 * row[b] + k] += Np[b] * z[k];
  }
  memset(out, 0, 3 * n_nodes * sizeof(double));
  for (int64_t k = 0; k < n_nodes; ++k)
  {
    const double* zk = work + 3 * k;
    if (zk[0] == 0.0 && zk[1] == 0.0 && zk[2] == 0.0)
      continue;
    for (int64_t s = slot_start[k]; s < slot_start[k + 1]; ++s)
    {
      const double* Dk = D + 9 * s;
      double* oj = out + 3 * slot_node[s];
      for (int j = 0; j < 3; ++j)
        oj[j] += Dk[j] * zk[0] + Dk[3 + j] * zk[1] + Dk[6 + j] * zk[2];
    }
  }
}

/* A pair block (P, 30, 30) on the positions of a pair's 10 nodes taken to their unknowns
 * (P, 60, 60): each node's displacement u (x moves one to one) and rotation theta (dx = A dtheta,
 * A = jacobian[node] (N, 3, 3)); rows and columns node by node, u then theta. */
void tc_chain_blocks(int64_t P, const int64_t* nodes, const double* jacobian, const double* M, double* out)
{
  for (int64_t p = 0; p < P; ++p)
  {
    const int64_t* pn = nodes + 10 * p;
    const double* Mp = M + 900 * p;
    double* Op = out + 3600 * p;
    for (int a = 0; a < 10; ++a)
    {
      const double* Aa = jacobian + 9 * pn[a];
      for (int b = 0; b < 10; ++b)
      {
        const double* Ab = jacobian + 9 * pn[b];
        double m[3][3], mA[3][3], Am[3][3], AmA[3][3];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            m[i][j] = Mp[30 * (3 * a + i) + 3 * b + j];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
          {
            mA[i][j] = m[i][0] * Ab[j] + m[i][1] * Ab[3 + j] + m[i][2] * Ab[6 + j];
            Am[i][j] = Aa[i] * m[0][j] + Aa[3 + i] * m[1][j] + Aa[6 + i] * m[2][j];
          }
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            AmA[i][j] = Aa[i] * mA[0][j] + Aa[3 + i] * mA[1][j] + Aa[6 + i] * mA[2][j];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
          {
            Op[60 * (6 * a + i) + 6 * b + j] = m[i][j];
            Op[60 * (6 * a + i) + 6 * b + 3 + j] = mA[i][j];
            Op[60 * (6 * a + 3 + i) + 6 * b + j] = Am[i][j];
            Op[60 * (6 * a + 3 + i) + 6 * b + 3 + j] = AmA[i][j];
          }
      }
    }
  }
}
