/* lib/core/src/hessian_psd_private.h: small dense eigensolvers and the analytic
 * eigensystem of the Hessian of W(C) = f(tr C^T C, det C) (Smith, de Goes,
 * Kim 2019), used to project each quadrature node's Hessian to positive
 * semidefinite for Newton's method (hessian_psd.c). */
#ifndef VARMESH_HESSIAN_PSD_PRIVATE_H
#define VARMESH_HESSIAN_PSD_PRIVATE_H

/* Cyclic Jacobi eigen-decomposition of the symmetric n x n matrix A
 * (row-major, n <= 9; destroyed): eigenvalues w[0..n), eigenvectors in the
 * columns of V (V[i*n + k] = component i of vector k), orthonormal. */
void vm_sym_eig(int n, double *A, double *w, double *V);

/* Signed SVD of a 3x3 C (row-major): C = U diag(sig) V^T with U and V
 * rotations (det +1), sig[0] >= sig[1] >= |sig[2]|, sig[2] < 0 when
 * det C < 0. */
void vm_svd3(const double *C, double *U, double sig[3], double *V);

/* The eigenpairs with negative eigenvalue of d2W/dC2 for a 3x3 C, where
 * f[0..5] = f, f_s, f_d, f_ss, f_sd, f_dd at (tr C^T C, det C): twists
 * U T_ij V^T (2 f_s + f_d sig_k), flips U L_ij V^T (2 f_s - f_d sig_k) and
 * the eigenvectors U diag(y) V^T of the 3x3 scaling block. Writes their
 * eigenvalues lam[k] < 0 and unit (Frobenius) directions D[k] (3x3
 * row-major); returns their number (0..9). */
int vm_psd_negative3(const double *C, const double f[6], double lam[9], double D[9][9]);

/* The same for an n x n symmetric Hessian given explicitly (n <= 9, by
 * Jacobi): negative eigenvalues and unit eigenvectors (D[k][0..n)). */
int vm_psd_negative_dense(int n, const double *H, double lam[9], double D[9][9]);

#endif
