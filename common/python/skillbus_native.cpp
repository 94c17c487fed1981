// skillbus_native: the Python extension module of skillbus's C++ hot paths.
//
//   QuietFrames  a Python lockstep participant's quiet frames acked without the
//                interpreter (py_quiet_frames.cpp, quiet_frames.hpp)
//   Sealer, Opener  bus authentication (py_auth.cpp: skillbus/auth.hpp's, for
//                skillbus.auth)
//   attach_channel_filter  the kernel filter of a udpm:// socket (py_channel_filter.cpp:
//                skillbus/channel_filter.hpp's, for skillbus.bus)
//   element_wire  a skill parameter's element in wm_element_t's bytes (py_tick_wire.cpp,
//                for skillbus.skill.tick_wire)
//   decode_clock  the lockstep clock read into the generated classes (py_lockstep_wire.cpp,
//                for skillbus.lockstep_wire)
//
// Python finds it through skillbus.native, which also honours SKILLBUS_NATIVE=0.
#include "glue.hpp"

namespace skillbus::native {

bool bytes_of(PyObject* o, Bytes& out, const char* what) {
  char* p = nullptr;
  Py_ssize_t n = 0;
  if (!PyBytes_Check(o) || PyBytes_AsStringAndSize(o, &p, &n) != 0) {
    PyErr_Format(PyExc_TypeError, "%s: bytes needed", what);
    return false;
  }
  out.assign(reinterpret_cast<uint8_t*>(p), reinterpret_cast<uint8_t*>(p) + n);
  return true;
}

bool utf8_of(PyObject* o, std::string& out, const char* what) {
  if (!PyUnicode_Check(o)) {
    PyErr_Format(PyExc_TypeError, "%s: str needed", what);
    return false;
  }
  // (surrogateescape: the bytes a name from argv or the environment was made of)
  PyObject* b = PyUnicode_AsEncodedString(o, "utf-8", "surrogateescape");
  if (!b) return false;
  out.assign(PyBytes_AS_STRING(b), static_cast<size_t>(PyBytes_GET_SIZE(b)));
  Py_DECREF(b);
  return true;
}

bool add_type(PyObject* module, PyTypeObject& type, const char* name) {
  if (PyType_Ready(&type) < 0) return false;
  Py_INCREF(&type);
  if (PyModule_AddObject(module, name, reinterpret_cast<PyObject*>(&type)) < 0) {
    Py_DECREF(&type);
    return false;
  }
  return true;
}

}  // namespace skillbus::native

namespace {
PyModuleDef module_def = {PyModuleDef_HEAD_INIT, "skillbus_native", "skillbus's C++ hot paths for Python.", -1,
                          nullptr};
}  // namespace

PyMODINIT_FUNC PyInit_skillbus_native() {
  PyObject* m = PyModule_Create(&module_def);
  if (!m) return nullptr;
  if (!skillbus::native::add_quiet_frames(m) || !skillbus::native::add_auth(m) ||
      !skillbus::native::add_channel_filter(m) || !skillbus::native::add_tick_wire(m) ||
      !skillbus::native::add_lockstep_wire(m)) {
    Py_DECREF(m);
    return nullptr;
  }
  return m;
}
