// Replaced by the features module sources (orb_extractor.cpp, stereo_matcher.cpp, ...).
namespace twistslam::features {}
