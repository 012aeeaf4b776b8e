# Install rules: `cmake --install <build> [--prefix P]` puts the public header under include/,
# the shared library under lib/, a CMake package (find_package(softhap) gives the imported
# target softhap::softhap) under lib/cmake/softhap, and softhap.pc under lib/pkgconfig. The
# optional dependencies are private to the shared library, so the package needs none of them.
include(CMakePackageConfigHelpers)

set(SOFTHAP_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/softhap)
set(SOFTHAP_FEATURES "")
if(SOFTHAP_WITH_CHOLMOD)
  list(APPEND SOFTHAP_FEATURES cholmod)
endif()
if(SOFTHAP_WITH_CCD)
  list(APPEND SOFTHAP_FEATURES ccd)
endif()

install(TARGETS softhap EXPORT softhapTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/softhap DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT softhapTargets NAMESPACE softhap:: DESTINATION ${SOFTHAP_CMAKE_DIR})

configure_package_config_file(cmake/softhapConfig.cmake.in ${CMAKE_CURRENT_BINARY_DIR}/softhapConfig.cmake
  INSTALL_DESTINATION ${SOFTHAP_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/softhapConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/softhapConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/softhapConfigVersion.cmake
  DESTINATION ${SOFTHAP_CMAKE_DIR})

# pkg-config: the prefix found from the .pc file's own place (${pcfiledir}), so that the tree
# works wherever `cmake --install --prefix` puts it.
file(RELATIVE_PATH SOFTHAP_PC_TO_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
configure_file(cmake/softhap.pc.in ${CMAKE_CURRENT_BINARY_DIR}/softhap.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/softhap.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
