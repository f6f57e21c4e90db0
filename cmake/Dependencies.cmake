# Third-party packages lightvol links against (Debian bookworm package names in README.md).
# Shared by the build and by the installed lightvolConfig.cmake.
include(CMakeFindDependencyMacro)
find_dependency(OpenMesh)
find_dependency(draco)
find_dependency(OpenImageIO)  # lightvol-image and the fuzz targets only
find_dependency(OpenEXR)  # lightvol-exr (its C core alone) and the fuzz targets only
find_dependency(nlohmann_json)
find_dependency(TBB)
find_dependency(Eigen3)
# lightvol::gl (the OpenGL renderer), when built, needs EGL; the core library does not.
find_package(OpenGL QUIET COMPONENTS EGL)

# Debian's OpenImageIO package names /usr/include/opencv4 as an include directory, which need not
# exist; drop it rather than pull in OpenCV.
if(TARGET OpenImageIO::OpenImageIO)
  get_target_property(_lv_oiio_inc OpenImageIO::OpenImageIO INTERFACE_INCLUDE_DIRECTORIES)
  if(_lv_oiio_inc)
    list(FILTER _lv_oiio_inc EXCLUDE REGEX "opencv")
    set_target_properties(OpenImageIO::OpenImageIO PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_lv_oiio_inc}")
  endif()
endif()
# Debian's draco target does not carry the Eigen include its glTF headers need.
if(TARGET draco::draco AND TARGET Eigen3::Eigen)
  set_property(TARGET draco::draco APPEND PROPERTY INTERFACE_LINK_LIBRARIES Eigen3::Eigen)
endif()
