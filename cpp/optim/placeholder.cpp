// Replaced by the optim module sources (pose_optimizer.cpp, bundle_adjustment.cpp, ...).
namespace twistslam::optim {}
