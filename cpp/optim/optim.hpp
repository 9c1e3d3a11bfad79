#pragma once
// Umbrella header of cpp/optim: pose-only optimisation and bundle adjustment.
#include "optim/bundle_adjustment.hpp"
#include "optim/pose_optimization.hpp"
