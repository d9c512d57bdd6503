#pragma once
// The sparse Cholesky factorisation of the cloth Hessians (CHOLMOD through
// Eigen): configured once for this machine, and the symbolic analysis kept per
// thread for the next solve of the same pattern. Internal to engine/cloth.
#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

#include <memory>

namespace drape::cloth::detail {

using SpMat = Eigen::SparseMatrix<double>;
using Cholmod = Eigen::CholmodDecomposition<SpMat, Eigen::Upper>;

/// A Cholesky object analysed for A's pattern: this thread's last one when the
/// pattern matches (`reused` true), a fresh analysis otherwise (configured:
/// supernodal, METIS, no OpenMP waits).
std::unique_ptr<Cholmod> take_analysed(const SpMat& A, bool& reused);
/// Keeps `llt` (analysed for A's pattern) for this thread's next solve.
void keep_analysed(std::unique_ptr<Cholmod> llt, const SpMat& A);
/// True when the factorisation in `llt` uses METIS (for traces).
bool uses_metis(Cholmod& llt);

} // namespace drape::cloth::detail
