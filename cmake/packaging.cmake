# CPack: one Debian package "ceilpose" with everything `cmake --install`
# places (ceilposed, ceilposectl, the unit, sysusers.d, /etc/ceilpose, the C
# client library, header and pkg-config file). docs/service.md shows how to
# build and install it. A system package: prefix /usr whatever the build's
# prefix (the unit and /etc/ceilpose are generated at install time for it).
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "ceilpose")
set(CPACK_PACKAGE_VENDOR "ceilpose")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_CONTACT "ceilpose maintainers <ceilpose@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")

set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION "misc")
set(CPACK_DEBIAN_PACKAGE_PRIORITY "optional")
if(CMAKE_CROSSCOMPILING)
  # dpkg-shlibdeps reads only this machine's libraries: scripts/build-arm64
  # computes Depends from the sysroot's packages (scripts/deb-depends) and
  # passes them to cpack as CPACK_DEBIAN_PACKAGE_DEPENDS.
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS OFF)
  if(CMAKE_SYSTEM_PROCESSOR STREQUAL "aarch64")
    set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "arm64")
  else()
    message(FATAL_ERROR "packaging: no Debian architecture for ${CMAKE_SYSTEM_PROCESSOR}")
  endif()
else()
  # Depends from the binaries' shared libraries (dpkg-shlibdeps).
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
endif()
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "Localizes a robot from coded ceiling markers seen by an upward camera and\npublishes its pose on POSIX shared memory and DDS (ROS 2 geometry_msgs).")

# Maintainer scripts, with the package's paths.
set(CEILPOSE_DEB_SYSUSERS_FILE "/usr/${CEILPOSE_SYSUSERSDIR}/ceilpose.conf")
set(CEILPOSE_DEB_CONFIG_FILE "/etc/ceilpose/ceilpose.yaml")
foreach(script postinst prerm postrm conffiles)
  configure_file(${CMAKE_CURRENT_LIST_DIR}/deb/${script}.in
                 ${CMAKE_BINARY_DIR}/deb/${script} @ONLY
                 FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE
                                  WORLD_READ WORLD_EXECUTE)
endforeach()
file(CHMOD ${CMAKE_BINARY_DIR}/deb/conffiles PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${CMAKE_BINARY_DIR}/deb/postinst ${CMAKE_BINARY_DIR}/deb/prerm ${CMAKE_BINARY_DIR}/deb/postrm
    ${CMAKE_BINARY_DIR}/deb/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)

include(CPack)
