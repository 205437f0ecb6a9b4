// The double instantiations of model/dense_numerics.hpp, compiled once for a build with
// ENDOHAPTICS_EXTERN_NUMERICS (core/separate_compilation.hpp; CMakeLists.txt,
// endohaptics_add_offline_library). Explicit instantiation definitions only: the function bodies
// stay in the header.
#include "endohaptics/model/dense_numerics.hpp"

namespace endohaptics::model::numerics {

template bool eigenvalues<double>(const Matrix<double>&, ComplexVector<double>&);
template LuSolution<double> lu_solve<double>(const Matrix<double>&, const Matrix<double>&);
template Matrix<double> exp<double>(const Matrix<double>&);
template Matrix<double> log<double>(const Matrix<double>&);

}  // namespace endohaptics::model::numerics
