# Every dependency is a Debian 12 package (scripts/install-deps.sh).
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(Ceres 2.1 REQUIRED)
find_package(fmt REQUIRED)
find_package(tomlplusplus REQUIRED)
find_package(CLI11 REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(FFTW3 REQUIRED IMPORTED_TARGET fftw3)
pkg_check_modules(MATIO REQUIRED IMPORTED_TARGET matio)
pkg_check_modules(PLPLOT REQUIRED IMPORTED_TARGET plplot)

find_path(CSV_INCLUDE_DIR csv.h REQUIRED)
find_library(CSV_LIBRARY csv REQUIRED)
add_library(jointlab_libcsv INTERFACE)
target_include_directories(jointlab_libcsv SYSTEM INTERFACE ${CSV_INCLUDE_DIR})
target_link_libraries(jointlab_libcsv INTERFACE ${CSV_LIBRARY})

find_path(SPECTRA_INCLUDE_DIR Spectra/SymEigsShiftSolver.h REQUIRED)
add_library(jointlab_spectra INTERFACE)
target_include_directories(jointlab_spectra SYSTEM INTERFACE ${SPECTRA_INCLUDE_DIR})

find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
add_library(jointlab_cholmod INTERFACE)
target_include_directories(jointlab_cholmod SYSTEM INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(jointlab_cholmod INTERFACE ${CHOLMOD_LIBRARY})

# glibc's vector maths library (part of libc6-dev), for signal/vector_math.cc; without it the
# scalar libm functions do the same work.
find_library(JOINTLAB_MVEC_LIBRARY mvec)
set(JOINTLAB_LIBMVEC "")
if(JOINTLAB_MVEC_LIBRARY AND CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
  set(JOINTLAB_LIBMVEC mvec)
endif()

find_package(Threads REQUIRED)
if(JOINTLAB_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(JOINTLAB_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
install(TARGETS jointlab_libcsv jointlab_spectra jointlab_cholmod EXPORT jointlabTargets)
