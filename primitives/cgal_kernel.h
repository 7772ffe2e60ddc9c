#pragma once
/// The CGAL kernel of the primitives module's floating-point geometry
/// (normal estimation, RANSAC). Private to primitives/*.cpp.

#include <CGAL/Simple_cartesian.h>

namespace csgvox::cgal {

using Kernel = CGAL::Simple_cartesian<double>;
using Point3 = Kernel::Point_3;
using Vector3 = Kernel::Vector_3;

}  // namespace csgvox::cgal
