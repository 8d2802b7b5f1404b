# CPack pre-build script (CPACK_PRE_BUILD_SCRIPTS, cmake/packaging.cmake):
# adds to the staged package tree what only the Debian package has.
if(NOT CPACK_GENERATOR STREQUAL "DEB")
  return()
endif()
set(root "${CPACK_TEMPORARY_DIRECTORY}")
set(prefix "${root}${CPACK_PACKAGING_INSTALL_PREFIX}")
set(dir_perm DIRECTORY_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
set(file_perm FILE_PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)

# /etc/canopen-gateway/gateway.yaml (a conffile, deploy/debian/conffiles):
# the example as installed, its paths already those of the package.
file(MAKE_DIRECTORY "${root}/etc/canopen-gateway")
file(CHMOD "${root}/etc" "${root}/etc/canopen-gateway" ${dir_perm})
file(COPY_FILE "${prefix}/${CPACK_CANOPEN_DATA_REL}/gateway.example.yaml" "${root}/etc/canopen-gateway/gateway.yaml")
file(CHMOD "${root}/etc/canopen-gateway/gateway.yaml" ${file_perm})

# The Debian changelog, one entry for this version (dated by
# SOURCE_DATE_EPOCH when set, for a reproducible package).
string(TIMESTAMP date "%a, %d %b %Y %H:%M:%S +0000" UTC)
set(doc "${prefix}/${CPACK_CANOPEN_DOC_REL}")
file(WRITE "${doc}/changelog"
"${CPACK_PACKAGE_NAME} (${CPACK_PACKAGE_VERSION}) unstable; urgency=medium

  * Built with CPack from the canopen-gateway sources, version ${CPACK_PACKAGE_VERSION}.

 -- ${CPACK_DEBIAN_PACKAGE_MAINTAINER}  ${date}
")
execute_process(COMMAND gzip -9nf "${doc}/changelog" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gzip of the Debian changelog failed: ${rc}")
endif()
file(CHMOD "${doc}/changelog.gz" ${file_perm})

# What lintian expects beyond CPack's strip (as dh_strip does).
file(GLOB programs "${prefix}/bin/*")
foreach(p ${programs})
  execute_process(COMMAND strip --remove-section=.comment --remove-section=.note "${p}" RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "strip ${p} failed: ${rc}")
  endif()
endforeach()

# Tags that do not apply, with the reasons (deploy/debian/lintian-overrides).
set(overrides "${prefix}/share/lintian/overrides")
file(MAKE_DIRECTORY "${overrides}")
file(CHMOD "${prefix}/share/lintian" "${overrides}" ${dir_perm})
file(COPY_FILE "${CPACK_CANOPEN_SOURCE_DIR}/deploy/debian/lintian-overrides" "${overrides}/${CPACK_PACKAGE_NAME}")
file(CHMOD "${overrides}/${CPACK_PACKAGE_NAME}" ${file_perm})
