#pragma once
// The variation step of DE/rand/1/bin (Storn & Price 1997), separate from the plugin so that tests can
// check the operator itself: donor indices, the j_rand rule and the bound repair.
#include <Eigen/Core>

#include "framework/optimizer.hpp"

namespace mhb::de {

// What to do with a mutant coordinate that leaves the box.
enum class BoundRepair {
    BetweenParentAndBound,  // redraw it uniformly between the parent's coordinate and the violated bound
    Clamp,                  // put it on the violated bound
};

struct Donors {
    Eigen::Index r1 = 0, r2 = 0, r3 = 0;
};

// Three indices drawn uniformly from [0, population) so that r1, r2, r3 and `target` are mutually
// distinct (population >= 4).
Donors draw_donors(Eigen::Index target, Eigen::Index population, Rng& rng);

// Writes into `trial` the DE/rand/1/bin trial vector of column `target` of `population`:
// v = x_r1 + F (x_r2 - x_r3), u_j = v_j if U(0,1) < CR or j == j_rand, else x_target,j; mutant
// coordinates outside the box are repaired by `repair`. Returns the donors used.
Donors make_trial(const Matrix& population, Eigen::Index target, double f, double cr, BoundRepair repair,
                  const Bounds& bounds, Rng& rng, Eigen::Ref<Vector> trial);

}  // namespace mhb::de
