// The analytic test deformations live in the library (geometry/synthetic_deformations.h) so
// the CLI can apply them to real meshes; the tests use them under retarget::test as well.
#pragma once

#include "geometry/synthetic_deformations.h"

namespace retarget::test {
using retarget::bend;
using retarget::bulge;
using retarget::rigid_motion;
using retarget::smoothstep;
using retarget::twist;
}  // namespace retarget::test
