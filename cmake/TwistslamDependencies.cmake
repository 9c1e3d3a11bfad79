# Finds the Debian-packaged C++ dependencies. Each failure names the apt package to install
# (`make setup` installs all of them).

# Debian's PCL config predates these policies and resets policies in its own scope, so the
# defaults are what reaches it: keep its FindBoost use and accept <PKG>_ROOT variables.
set(CMAKE_POLICY_DEFAULT_CMP0144 NEW)
set(CMAKE_POLICY_DEFAULT_CMP0167 OLD)

macro(twistslam_require package apt_package)
  find_package(${package} ${ARGN} QUIET)
  if(NOT ${package}_FOUND)
    message(FATAL_ERROR
      "twistslam needs ${package} (${ARGN}), which CMake could not find.\n"
      "On Debian/Ubuntu: sudo apt-get install ${apt_package}   (or run `make setup`)")
  endif()
  message(STATUS "twistslam: found ${package} ${${package}_VERSION}")
endmacro()

twistslam_require(Eigen3 libeigen3-dev 3.3 NO_MODULE)
twistslam_require(Ceres libceres-dev 2.0)
twistslam_require(OpenCV libopencv-dev 4 COMPONENTS core imgproc features2d calib3d)
# PCL: only the modules we use; its config drags in VTK (hence C in project()).
twistslam_require(PCL libpcl-dev 1.10 COMPONENTS common kdtree registration)
