// The double instantiations of estimation/dare.hpp's dynamic-size solver, compiled once for a
// build with ENDOHAPTICS_EXTERN_NUMERICS (core/separate_compilation.hpp; CMakeLists.txt,
// endohaptics_add_offline_library). Explicit instantiation definitions only: the function bodies
// stay in the header.
#include "endohaptics/estimation/dare.hpp"

namespace endohaptics::estimation::detail {

template DareSolution<Eigen::Dynamic, double> solve_filter_dare_dynamic<double>(
    const DynamicMatrix<double>&, const DynamicMatrix<double>&, const DynamicMatrix<double>&,
    const DynamicMatrix<double>&, const DareOptions<double>&, double);
template DynamicMatrix<double> filter_riccati_defect<double>(const DynamicMatrix<double>&,
                                                             const DynamicMatrix<double>&,
                                                             const DynamicMatrix<double>&,
                                                             const DynamicMatrix<double>&,
                                                             const DynamicMatrix<double>&);

}  // namespace endohaptics::estimation::detail
