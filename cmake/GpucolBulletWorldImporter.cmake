# Bullet's BulletWorldImporter and BulletFileLoader libraries (Debian's libbullet-extras-dev) as the imported target
# gpucol::BulletWorldImporter. Included by the build and by the installed gpucolConfig.cmake, so that a project
# linking gpucol::gpucol finds them the same way.
if(NOT TARGET gpucol::BulletWorldImporter)
  find_library(GPUCOL_BULLET_WORLD_IMPORTER_LIBRARY BulletWorldImporter REQUIRED)
  find_library(GPUCOL_BULLET_FILE_LOADER_LIBRARY BulletFileLoader REQUIRED)
  add_library(gpucol::BulletWorldImporter UNKNOWN IMPORTED)
  set_target_properties(gpucol::BulletWorldImporter PROPERTIES
    IMPORTED_LOCATION "${GPUCOL_BULLET_WORLD_IMPORTER_LIBRARY}"
    INTERFACE_LINK_LIBRARIES "${GPUCOL_BULLET_FILE_LOADER_LIBRARY}")
endif()
