// The one copy of the Eigen decompositions that src/core/internal/eigen_instances.h declares.
#include "core/internal/eigen_instances.h"

CTID_EIGEN_INSTANCES()
