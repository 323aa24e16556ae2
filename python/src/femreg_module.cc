// The femreg Python module (pybind11): scenes, meshes, materials and options; the Tracker
// with numpy in and out; the forward solve; the mesh, cloud and depth-image readers and
// writers; the files of depth cameras (NumPy frames, intrinsics, TUM RGB-D sequences). Every femreg::Status error becomes femreg.Error with the C++ message; a wrong
// array shape or an unknown option name is a ValueError.
//
// The bindings live by subject in the Bind* files (bindings.h); this file is the module
// init, which calls them in order.
#include <exception>

#include "bindings.h"
#include "femreg/blas_kernels.h"
#include "femreg/version.h"

PYBIND11_MODULE(_femreg, m) {
  using namespace femreg;           // NOLINT
  using namespace femreg::python;   // NOLINT
  m.doc() = "femreg: physics-regularized non-rigid registration of tetrahedral meshes to "
            "point clouds (C++ core, pybind11 bindings).";
  // The library's version (CMakeLists.txt's project() line): femreg.__version__.
  m.attr("__version__") = femreg::Version();

  // The BLAS kernels in use, and the switch to this CPU's best where OpenBLAS did not know it
  // (femreg/blas_kernels.h); __init__.py switches by itself only if femreg's import loaded that OpenBLAS.
  m.def("blas_kernels", &BlasCoreName,
        "The kernels of the loaded OpenBLAS ('SkylakeX', 'Haswell', ...; '' for another BLAS).");
  m.def("_blas_library", &BlasLibraryPath);
  m.def("use_better_blas_kernels", &UseBetterBlasKernels,
        "Switches OpenBLAS to this CPU's best kernels where it took slower ones (a CPU newer than "
        "the OpenBLAS) and OPENBLAS_CORETYPE is unset; returns the kernels in use. Only safe "
        "while no other thread calls the BLAS (numpy included): importing femreg does it "
        "itself when the import loaded OpenBLAS.");

  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      error(e.what());
    }
  });

  BindOptions(m);
  BindMeshes(m);
  BindPointClouds(m);
  BindDepthImages(m);
  BindCameraFiles(m);
  BindScene(m);
  BindTracker(m);
  BindSimulate(m);
}
