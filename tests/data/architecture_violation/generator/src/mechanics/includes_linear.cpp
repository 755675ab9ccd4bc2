// A tree for the test architecture_map_rejects: a private header of generator/linear/ included
// from generator/mechanics/, a stage reaching into a later one.
#include "linear/sample_points.hpp"
