// Plan design: the relaxation's design (filter/design/bound.hpp, time over a library of segments)
// rounded into a plan the table can run, a seed of the search (filter/design/search.hpp).
// docs/methods/design.md "The relaxed design as a plan".
#pragma once

#include "filter/design/bound.hpp"

namespace sinscal {

/// The relaxed design `bound` of `lib` as a rotation plan of at most `bound.budget_s` s on
/// `table` at `site`, named `name`: from the library's start (body x up) a walk over the
/// orientations that takes, at each, the turn of most remaining design count (time / duration,
/// one per turn taken) while it has some left, or the first turn of the shortest way to an
/// orientation that has one; each orientation's rest time shared among its visits and the dwells
/// scaled to the time left. Throws std::invalid_argument when the budget does not hold one turn.
Plan rounded_design(const InformationLibrary& lib, const DesignBound& bound, const TableSpec& table,
                    const Site& site, const std::string& name = "relaxed");

}  // namespace sinscal
