// skillbus_native.element_wire(element) -> bytes or None: a skill parameter's element as
// its wm_element_t encodes (skillbus.skill.tick_wire.element_bytes: id, type, label, then
// each property's key and values), written from the Python objects in one pass.
//
// Why: a skill process answers every tick with every parameter, and each element
// parameter carries its properties; in Python that was a few microseconds an element,
// most of the reply's encoding in the demo (docs/benchmarks.md). Only the regular case is
// written here: an element whose properties are its own (not a reader copy's still
// shared), values of exactly str, int (64-bit), float and bool, text that is UTF-8. For
// anything else the answer is None and Python's encoder writes it (or raises as it does).
// tests/py/test_tick_wire.py compares the two on random elements.
#include <cstdint>
#include <cstring>
#include <string>

#include "glue.hpp"
#include "skillbus_msgs/wm_value_t.hpp"

namespace skillbus::native {

namespace {

using skillbus_msgs::wm_value_t;

void put_u32(std::string& out, uint32_t v) {
  const char b[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  out.append(b, 4);
}

void put_u64(std::string& out, uint64_t v) {
  char b[8];
  for (int i = 0; i < 8; ++i) b[i] = char(v >> (56 - 8 * i));
  out.append(b, 8);
}

// LCM's string: u32 length with the NUL, the bytes, the NUL. False for a str that is not
// UTF-8 (a lone surrogate): Python's encoder raises for it.
bool put_text(std::string& out, PyObject* s) {
  Py_ssize_t n = 0;
  const char* p = PyUnicode_AsUTF8AndSize(s, &n);
  if (!p) {
    PyErr_Clear();
    return false;
  }
  put_u32(out, static_cast<uint32_t>(n + 1));
  out.append(p, static_cast<size_t>(n));
  out.push_back('\0');
  return true;
}

// A wm_value_t's fields after its type and string: i (int64), f (double), b (int8).
void put_numbers(std::string& out, int64_t i, double f, bool b) {
  put_u64(out, static_cast<uint64_t>(i));
  uint64_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  put_u64(out, bits);
  out.push_back(b ? 1 : 0);
}

const char kEmptyText[5] = {0, 0, 0, 1, 0};

// One property value as tick_wire._wm_value writes it; false when Python must write it.
bool put_value(std::string& out, PyObject* v) {
  if (PyFloat_CheckExact(v)) {
    out.push_back(static_cast<char>(wm_value_t::FLOAT));
    out.append(kEmptyText, 5);
    put_numbers(out, 0, PyFloat_AS_DOUBLE(v), false);
  } else if (PyBool_Check(v)) {  // (before int: a bool is an int; bool has no subclasses)
    out.push_back(static_cast<char>(wm_value_t::BOOL));
    out.append(kEmptyText, 5);
    put_numbers(out, 0, 0.0, v == Py_True);
  } else if (PyLong_CheckExact(v)) {
    int overflow = 0;
    const long long i = PyLong_AsLongLongAndOverflow(v, &overflow);
    if (overflow || (i == -1 && PyErr_Occurred())) {  // (Python's struct.error, from Python)
      PyErr_Clear();
      return false;
    }
    out.push_back(static_cast<char>(wm_value_t::INT));
    out.append(kEmptyText, 5);
    put_numbers(out, i, 0.0, false);
  } else if (PyUnicode_CheckExact(v)) {
    out.push_back(static_cast<char>(wm_value_t::STRING));
    if (!put_text(out, v)) return false;
    put_numbers(out, 0, 0.0, false);
  } else {
    return false;  // (a subclass, or a type that cannot be stored: Python's answer)
  }
  return true;
}

// A borrowed exact str from `d`, or null.
PyObject* text_item(PyObject* d, const char* key) {
  PyObject* v = PyDict_GetItemString(d, key);
  return v && PyUnicode_CheckExact(v) ? v : nullptr;
}

// The property's attribute `name` (a new reference), or null with no error set.
PyObject* attribute(PyObject* o, PyObject* name) {
  PyObject* v = PyObject_GetAttr(o, name);
  if (!v) PyErr_Clear();
  return v;
}

PyObject* element_wire(PyObject*, PyObject* e) {
  static PyObject* key_name = PyUnicode_InternFromString("_key");
  static PyObject* values_name = PyUnicode_InternFromString("_values");
  PyObject* d = PyObject_GenericGetDict(e, nullptr);
  if (!d) {
    PyErr_Clear();
    Py_RETURN_NONE;
  }
  std::string out;
  bool ok = PyDict_CheckExact(d);
  PyObject* props = ok ? PyDict_GetItemString(d, "_properties") : nullptr;  // (absent: a reader copy)
  PyObject *id = ok ? text_item(d, "_id") : nullptr, *type = ok ? text_item(d, "_type") : nullptr,
           *label = ok ? text_item(d, "_label") : nullptr;
  ok = props && PyDict_CheckExact(props) && id && type && label;
  if (ok) {
    out.reserve(64 + 96 * static_cast<size_t>(PyDict_GET_SIZE(props)));
    ok = put_text(out, id) && put_text(out, type) && put_text(out, label);
  }
  if (ok) {
    // (a list of them first: reading an attribute may run Python code, which may change the dict)
    PyObject* all = PyDict_Values(props);
    if (!all) PyErr_Clear();
    ok = all != nullptr;
    const Py_ssize_t count = ok ? PyList_GET_SIZE(all) : 0;
    put_u32(out, static_cast<uint32_t>(count));
    for (Py_ssize_t j = 0; ok && j < count; ++j) {
      PyObject* p = PyList_GET_ITEM(all, j);
      PyObject* key = attribute(p, key_name);
      PyObject* values = key ? attribute(p, values_name) : nullptr;
      ok = key && values && PyUnicode_CheckExact(key) && PyList_CheckExact(values) && put_text(out, key);
      if (ok) {
        const Py_ssize_t n = PyList_GET_SIZE(values);
        put_u32(out, static_cast<uint32_t>(n));
        for (Py_ssize_t i = 0; ok && i < n; ++i) ok = put_value(out, PyList_GET_ITEM(values, i));
      }
      Py_XDECREF(key);
      Py_XDECREF(values);
    }
    Py_XDECREF(all);
  }
  Py_DECREF(d);
  if (!ok) Py_RETURN_NONE;
  return PyBytes_FromStringAndSize(out.data(), static_cast<Py_ssize_t>(out.size()));
}

PyMethodDef methods[] = {
    {"element_wire", element_wire, METH_O,
     "element_wire(element) -> bytes | None: the element as wm_element_t encodes, or None when Python must "
     "encode it (skillbus.skill.tick_wire)."},
    {nullptr, nullptr, 0, nullptr}};

}  // namespace

bool add_tick_wire(PyObject* module) { return PyModule_AddFunctions(module, methods) == 0; }

}  // namespace skillbus::native
