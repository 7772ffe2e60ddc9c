#pragma once
/// Names a designer would give a primitive, from its type, its size and
/// whether it adds material or cuts it: plate, block, rib, hub, boss, dome,
/// ring, taper, side (adding); hole, bore, slot, pocket, fillet, chamfer,
/// recess, cut (cutting).

#include <string>

#include "core/primitive.h"

namespace csgvox {

/// The role of `primitive` in a part of diagonal `partDiagonal` (scan
/// units); `cuts`: it removes material (it is subtracted).
std::string roleName(const Primitive& primitive, bool cuts, double partDiagonal);

}  // namespace csgvox
