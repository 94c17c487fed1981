// What the CPython glue files of skillbus_native share (skillbus_native.cpp: the module).
#pragma once

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <memory>
#include <string>

#include "skillbus/bus.hpp"

namespace skillbus::native {

// `o` (bytes) copied into `out`; false with a TypeError naming `what` otherwise.
bool bytes_of(PyObject* o, Bytes& out, const char* what);
// `o` (str) as UTF-8 (surrogateescape) into `out`; false with a TypeError otherwise.
bool utf8_of(PyObject* o, std::string& out, const char* what);

// `type` made ready and added to `module` as `name`; false with a Python error set.
bool add_type(PyObject* module, PyTypeObject& type, const char* name);

struct SharedOpener;
// The opener of a skillbus_native.Opener object; null for anything else.
std::shared_ptr<SharedOpener> opener_of(PyObject* o);

// Each adds its type(s) to the module; false with a Python error set.
bool add_quiet_frames(PyObject* module);
bool add_auth(PyObject* module);
bool add_channel_filter(PyObject* module);
bool add_tick_wire(PyObject* module);
bool add_lockstep_wire(PyObject* module);

}  // namespace skillbus::native
