// linespace-profile --lookups: what a Line Space lookup costs alone, apart from the walk around it.
#pragma once

#include "common/kernels/layouts.h"
#include "common/structure/accel.h"

#include <vector>

namespace ls {

// Collects the lookups a nearest-first walk of the flat structure's binary BVH makes for `rays` (the
// reference kernel's lookups), then times ls_lookup alone on them, one thread: in that order, in a
// shuffled order (each lookup's data as cold as the structure's size allows), and the first 1,024
// of them over and over (cached).  Prints ns per lookup, the answers' shares and the bytes a shaft
// costs.  Throws InputError for a structure without a Line Space or a two-level one.
void time_lookups(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays, int repeat);

}  // namespace ls
