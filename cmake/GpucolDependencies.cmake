# Every dependency comes from Debian's packages (scripts/deps.sh installs them).
find_package(PkgConfig REQUIRED)
# Debian's BulletConfig.cmake carries relative paths, so Bullet is found through pkg-config.
pkg_check_modules(BULLET REQUIRED IMPORTED_TARGET bullet>=3.0)
# Bullet's world importer (libbullet-extras-dev), which gpucol::WorldImporter extends; bullet.pc does not name it.
include(${CMAKE_CURRENT_LIST_DIR}/GpucolBulletWorldImporter.cmake)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
if(GPUCOL_WITH_OPENCL)
  find_package(OpenCL REQUIRED)
endif()
