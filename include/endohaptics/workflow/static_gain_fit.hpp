//! @file
//! The static-gain baseline of the identify workflow: y = D u + c by least squares over every
//! segment (no dynamics), as a SubspaceModel with one constant state per output (A = I, B = 0,
//! C = I, x0 = c). Signals keep their units. Configuration time: throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <Eigen/QR>
#include <span>
#include <string>
#include <utility>

#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/workflow/error_context.hpp"

namespace endohaptics::workflow {

using namespace endohaptics::identification;  // the workflow composes the identification area

//! y = D u + c by least squares over every segment, as a model file with one constant state per
//! output (A = I, B = 0, C = I, x0 = c). Throws Error when the regression is singular.
[[nodiscard]] inline SubspaceModel fit_static_gain(std::span<const DataSet> data,
                                                   double sample_time) {
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
