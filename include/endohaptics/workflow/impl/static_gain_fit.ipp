//! @file
//! Function bodies of workflow/static_gain_fit.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/static_gain_fit.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL SubspaceModel fit_static_gain(std::span<const DataSet> data, double sample_time) {
  const Eigen::Index nu = data.front().u.cols();
  const Eigen::Index ny = data.front().y.cols();
  Eigen::Index rows = 0;
  for (const DataSet& d : data) rows += d.u.rows();
  Eigen::MatrixXd X(rows, nu + 1);
  Eigen::MatrixXd Y(rows, ny);
  Eigen::Index r = 0;
  for (const DataSet& d : data) {
    X.block(r, 0, d.u.rows(), nu) = d.u;
    X.block(r, nu, d.u.rows(), 1).setOnes();
    Y.middleRows(r, d.y.rows()) = d.y;
    r += d.u.rows();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  if (qr.rank() < X.cols()) {
    detail::fail("static gain: the inputs are constant or collinear (rank " +
                 std::to_string(qr.rank()) + " of " + std::to_string(X.cols()) + ")");
  }
  const Eigen::MatrixXd theta = qr.solve(Y);  // (nu + 1) x ny
  model::DynamicStateSpace<> gain(Eigen::MatrixXd::Identity(ny, ny), Eigen::MatrixXd::Zero(ny, nu),
                                  Eigen::MatrixXd::Identity(ny, ny), theta.topRows(nu).transpose(),
                                  sample_time);
  const Eigen::VectorXd offset = theta.row(nu).transpose();
  gain.reset(offset);
  return SubspaceModel{
      .state_space = std::move(gain), .initial_states = {offset}, .order = static_cast<int>(ny)};
}

}  // namespace endohaptics::workflow
