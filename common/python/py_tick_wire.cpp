// skillbus_native.element_wire(element) -> bytes or None: a skill parameter's element as
// its wm_element_t encodes (skillbus.skill.tick_wire.element_bytes: id, type, label, then
// each property's key and values), written from the Python objects in one pass; and
// skillbus_native.params_wire(params) -> bytes: a tick reply's parameters, each as
// tick_wire.param_bytes writes it from the skill's Param.
//
// Why: a skill process answers every tick with every parameter, and each element
// parameter carries its properties; in Python that was a few microseconds an element, then
// 40-70 µs a reply of the demo's (docs/benchmarks.md). Only the regular case is written
// here: an element whose properties are its own, values of exactly str, int (64-bit),
// float and bool, text that is UTF-8, a parameter whose lists are lists. For anything else
// element_wire answers None; params_wire hands an element it leaves (a tick's reader
// copies: Python keeps their bytes per source, tick after tick) to Python's
// python_element_bytes, and any other parameter to Python's param_bytes, which writes it
// or raises as it does. tests/py/test_tick_wire.py compares the two on random elements and
// parameters.
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>

#include "glue.hpp"
#include "skillbus_msgs/skill_value_t.hpp"
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

// Attribute names, interned once (add_tick_wire: the module does not load without them).
struct Names {
  PyObject *key, *values, *defaults, *data_type, *type, *description, *param_type, *options;
};
Names names;

// What put_scalar did with a value.
enum class Scalar { kWritten, kNotOne, kRefused };

// A value of exactly float, bool, int (64-bit) or str as a `Value` (wm_value_t or
// skill_value_t) writes it up to its numbers: the type, the string, i, f, b. kNotOne for
// any other type (a subclass too); kRefused for an int beyond 64 bits or a str that is not
// UTF-8 (Python raises for those).
template <class Value>
Scalar put_scalar(std::string& out, PyObject* v) {
  if (PyFloat_CheckExact(v)) {
    out.push_back(static_cast<char>(Value::FLOAT));
    out.append(kEmptyText, 5);
    put_numbers(out, 0, PyFloat_AS_DOUBLE(v), false);
  } else if (PyBool_Check(v)) {  // (before int: a bool is an int; bool has no subclasses)
    out.push_back(static_cast<char>(Value::BOOL));
    out.append(kEmptyText, 5);
    put_numbers(out, 0, 0.0, v == Py_True);
  } else if (PyLong_CheckExact(v)) {
    int overflow = 0;
    const long long i = PyLong_AsLongLongAndOverflow(v, &overflow);
    if (overflow || (i == -1 && PyErr_Occurred())) {  // (Python's struct.error, from Python)
      PyErr_Clear();
      return Scalar::kRefused;
    }
    out.push_back(static_cast<char>(Value::INT));
    out.append(kEmptyText, 5);
    put_numbers(out, i, 0.0, false);
  } else if (PyUnicode_CheckExact(v)) {
    out.push_back(static_cast<char>(Value::STRING));
    if (!put_text(out, v)) return Scalar::kRefused;
    put_numbers(out, 0, 0.0, false);
  } else {
    return Scalar::kNotOne;
  }
  return Scalar::kWritten;
}

// One property value as tick_wire._wm_value writes it; false when Python must write it (a
// subclass, or a type that cannot be stored: Python's answer).
bool put_value(std::string& out, PyObject* v) { return put_scalar<wm_value_t>(out, v) == Scalar::kWritten; }

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

// The properties in `all` (a list of Property objects) as wm_element_t writes them after
// the names; false when Python must write them.
bool put_properties(std::string& out, PyObject* all) {
  const Py_ssize_t count = PyList_GET_SIZE(all);
  put_u32(out, static_cast<uint32_t>(count));
  bool ok = true;
  for (Py_ssize_t j = 0; ok && j < count; ++j) {
    PyObject* p = PyList_GET_ITEM(all, j);
    PyObject* key = attribute(p, names.key);
    PyObject* values = key ? attribute(p, names.values) : nullptr;
    ok = key && values && PyUnicode_CheckExact(key) && PyList_CheckExact(values) && put_text(out, key);
    if (ok) {
      const Py_ssize_t n = PyList_GET_SIZE(values);
      put_u32(out, static_cast<uint32_t>(n));
      for (Py_ssize_t i = 0; ok && i < n; ++i) ok = put_value(out, PyList_GET_ITEM(values, i));
    }
    Py_XDECREF(key);
    Py_XDECREF(values);
  }
  return ok;
}

// An element whose properties are its own as wm_element_t encodes (id, type, label,
// properties). False when Python must write it (a reader copy among them); `out` may then
// hold part of it.
bool put_element(std::string& out, PyObject* e) {
  PyObject* d = PyObject_GenericGetDict(e, nullptr);
  if (!d) {
    PyErr_Clear();
    return false;
  }
  bool ok = PyDict_CheckExact(d);
  PyObject* props = ok ? PyDict_GetItemString(d, "_properties") : nullptr;  // (absent: a reader copy)
  // (held: reading the properties' attributes may run Python code, which may change the dict)
  PyObject *id = ok ? text_item(d, "_id") : nullptr, *type = ok ? text_item(d, "_type") : nullptr,
           *label = ok ? text_item(d, "_label") : nullptr;
  Py_XINCREF(id);
  Py_XINCREF(type);
  Py_XINCREF(label);
  // (a list of them first: reading an attribute may run Python code, which may change the dict)
  PyObject* all = nullptr;
  if (ok && props && PyDict_CheckExact(props)) {
    all = PyDict_Values(props);
    if (!all) PyErr_Clear();
  }
  ok = all && id && type && label;
  if (ok) {
    out.reserve(out.size() + 64 + 96 * static_cast<size_t>(PyList_GET_SIZE(all)));
    ok = put_text(out, id) && put_text(out, type) && put_text(out, label) && put_properties(out, all);
  }
  Py_XDECREF(all);
  Py_XDECREF(id);
  Py_XDECREF(type);
  Py_XDECREF(label);
  Py_DECREF(d);
  return ok;
}

PyObject* element_wire(PyObject*, PyObject* e) {
  std::string out;
  if (!put_element(out, e)) Py_RETURN_NONE;
  return PyBytes_FromStringAndSize(out.data(), static_cast<Py_ssize_t>(out.size()));
}

// -- a tick reply's parameters -----------------------------------------------------------

struct ParamWire {
  PyObject* type_names = nullptr;   // TYPE_NAMES: a parameter's Python type -> its data_type name
  PyObject* element_type = nullptr;  // skillbus.world.element.Element
  PyObject* param_bytes = nullptr;   // Python's param_bytes(p), for what is not the regular case
  // Python's python_element_bytes(e), for an element put_element leaves: a reader copy
  // (its bytes kept per source there, tick after tick), a value of another type.
  PyObject* element_bytes = nullptr;
};
ParamWire param_wire;

// wm_element_t() as tick_wire._NO_ELEMENT: three empty strings and no properties.
void put_no_element(std::string& out) {
  for (int i = 0; i < 3; ++i) out.append(kEmptyText, 5);
  put_u32(out, 0);
}

void put_i32(std::string& out, int32_t v) { put_u32(out, static_cast<uint32_t>(v)); }

// One skill_value_t as tick_wire.value_bytes writes it; false when Python must write it.
bool put_skill_value(std::string& out, PyObject* v) {
  using skillbus_msgs::skill_value_t;
  const Scalar scalar = put_scalar<skill_value_t>(out, v);
  if (scalar == Scalar::kRefused) return false;
  if (scalar == Scalar::kNotOne) {
    const int is_element = PyObject_IsInstance(v, param_wire.element_type);
    if (is_element <= 0) {
      PyErr_Clear();
      return false;  // (a list or dict as JSON, or a value that cannot be sent: Python's)
    }
    out.push_back(static_cast<char>(skill_value_t::ELEMENT));
    out.append(kEmptyText, 5);
    put_numbers(out, 0, 0.0, false);
    const size_t mark = out.size();
    if (put_element(out, v)) return true;
    out.resize(mark);
    PyObject* b = PyObject_CallOneArg(param_wire.element_bytes, v);
    const bool ok = b && PyBytes_Check(b);
    if (ok) out.append(PyBytes_AS_STRING(b), static_cast<size_t>(PyBytes_GET_SIZE(b)));
    Py_XDECREF(b);
    if (!ok) PyErr_Clear();  // (what it raised, param_bytes raises again for the parameter)
    return ok;
  }
  put_no_element(out);
  return true;
}

// `values` (an exact list) as a count and its skill_value_t's; false when Python must.
// (over a copy of the list: an element's truthiness or isinstance may run Python code)
bool put_skill_values(std::string& out, PyObject* values) {
  if (!values || !PyList_CheckExact(values)) return false;
  PyObject* held = PyList_GetSlice(values, 0, PyList_GET_SIZE(values));
  if (!held) {
    PyErr_Clear();
    return false;
  }
  const Py_ssize_t n = PyList_GET_SIZE(held);
  put_i32(out, static_cast<int32_t>(n));
  bool ok = true;
  for (Py_ssize_t i = 0; ok && i < n; ++i) ok = put_skill_value(out, PyList_GET_ITEM(held, i));
  Py_DECREF(held);
  return ok;
}

// Attributes of a Param, in the order param_bytes reads them (a property's getter may run
// Python code: read as Python reads them, each held until the parameter is written).
struct ParamFields {
  PyObject *defaults = nullptr, *data_type = nullptr, *concept = nullptr, *values = nullptr, *key = nullptr,
           *description = nullptr, *kind = nullptr, *type_name = nullptr, *options = nullptr;
  ~ParamFields() {
    for (PyObject* o : {defaults, data_type, concept, values, key, description, kind, type_name, options}) Py_XDECREF(o);
  }
};

// The fields of `p` (false, with no error set, at the first that is not the regular case).
bool read_param(PyObject* p, ParamFields& f) {
  f.defaults = attribute(p, names.defaults);
  if (!f.defaults || !PyList_CheckExact(f.defaults)) return false;
  f.data_type = attribute(p, names.data_type);
  if (!f.data_type) return false;
  if (f.data_type == param_wire.element_type && PyList_GET_SIZE(f.defaults) > 0) {
    PyObject* first = PyList_GET_ITEM(f.defaults, 0);
    Py_INCREF(first);
    f.concept = attribute(first, names.type);
    Py_DECREF(first);
    if (!f.concept || !PyUnicode_CheckExact(f.concept)) return false;
  }
  f.values = attribute(p, names.values);
  f.key = f.values ? attribute(p, names.key) : nullptr;
  f.description = f.key ? attribute(p, names.description) : nullptr;
  f.kind = f.description ? attribute(p, names.param_type) : nullptr;
  if (!f.kind || !PyUnicode_CheckExact(f.key) || !PyUnicode_CheckExact(f.description) || !PyLong_Check(f.kind))
    return false;
  f.type_name = PyDict_GetItemWithError(param_wire.type_names, f.data_type);
  if (!f.type_name) {
    PyErr_Clear();  // (unhashable, or no such type: Python's KeyError or TypeError)
    return false;
  }
  Py_INCREF(f.type_name);
  return PyUnicode_CheckExact(f.type_name);
}

// One skill_param_t as tick_wire.param_bytes writes it from a Param; false, with no error
// set, when Python must write it (anything but the regular case).
bool put_param(std::string& out, PyObject* p) {
  ParamFields f;
  if (!read_param(p, f)) return false;
  int overflow = 0;
  const long kind = PyLong_AsLongAndOverflow(f.kind, &overflow);
  if (overflow || (kind == -1 && PyErr_Occurred()) || kind < -128 || kind > 127) {
    PyErr_Clear();  // (Python's struct.error)
    return false;
  }
  bool ok = put_text(out, f.key) && put_text(out, f.description);
  out.push_back(static_cast<char>(kind));
  ok = ok && put_text(out, f.type_name);
  if (ok && f.concept) {
    ok = put_text(out, f.concept);
  } else if (ok) {
    out.append(kEmptyText, 5);
  }
  ok = ok && put_skill_values(out, f.values) && put_skill_values(out, f.defaults);
  if (ok) {
    f.options = attribute(p, names.options);
    ok = f.options && PyList_CheckExact(f.options);
  }
  if (ok) {  // (nothing below runs Python code)
    const Py_ssize_t n = PyList_GET_SIZE(f.options);
    put_i32(out, static_cast<int32_t>(n));
    for (Py_ssize_t i = 0; ok && i < n; ++i) {
      PyObject* o = PyList_GET_ITEM(f.options, i);
      ok = PyUnicode_CheckExact(o) && put_text(out, o);  // (str(o) of anything else: Python's)
    }
  }
  if (PyErr_Occurred()) PyErr_Clear();
  return ok;
}

// params_wire(params) -> bytes: the skill_param_t's of a list of Params, as b"".join of
// tick_wire.param_bytes: the regular case here, any other parameter by param_bytes
// itself (which writes it, or raises what it raises).
PyObject* params_wire(PyObject*, PyObject* params) {
  if (!param_wire.param_bytes) {
    PyErr_SetString(PyExc_RuntimeError, "params_wire: set_param_wire was not called");
    return nullptr;
  }
  if (!PyList_CheckExact(params)) {
    PyErr_SetString(PyExc_TypeError, "params_wire: a list of Params needed");
    return nullptr;
  }
  std::string out;
  // (a list of them first: a parameter's attributes may run Python code)
  PyObject* all = PyList_GetSlice(params, 0, PyList_GET_SIZE(params));
  if (!all) return nullptr;
  for (Py_ssize_t i = 0; i < PyList_GET_SIZE(all); ++i) {
    PyObject* p = PyList_GET_ITEM(all, i);
    const size_t mark = out.size();
    if (put_param(out, p)) continue;
    out.resize(mark);
    PyObject* b = PyObject_CallOneArg(param_wire.param_bytes, p);
    if (!b || !PyBytes_Check(b)) {
      if (b) PyErr_SetString(PyExc_TypeError, "params_wire: param_bytes did not return bytes");
      Py_XDECREF(b);
      Py_DECREF(all);
      return nullptr;
    }
    out.append(PyBytes_AS_STRING(b), static_cast<size_t>(PyBytes_GET_SIZE(b)));
    Py_DECREF(b);
  }
  Py_DECREF(all);
  return PyBytes_FromStringAndSize(out.data(), static_cast<Py_ssize_t>(out.size()));
}

PyObject* set_param_wire(PyObject*, PyObject* args) {
  PyObject *names = nullptr, *element = nullptr, *fallback = nullptr, *element_fallback = nullptr;
  if (!PyArg_ParseTuple(args, "O!OOO", &PyDict_Type, &names, &element, &fallback, &element_fallback)) return nullptr;
  if (!PyType_Check(element) || !PyCallable_Check(fallback) || !PyCallable_Check(element_fallback)) {
    PyErr_SetString(PyExc_TypeError, "set_param_wire(type_names, Element, param_bytes, python_element_bytes)");
    return nullptr;
  }
  Py_INCREF(names);
  Py_INCREF(element);
  Py_INCREF(fallback);
  Py_INCREF(element_fallback);
  Py_XSETREF(param_wire.type_names, names);
  Py_XSETREF(param_wire.element_type, element);
  Py_XSETREF(param_wire.param_bytes, fallback);
  Py_XSETREF(param_wire.element_bytes, element_fallback);
  Py_RETURN_NONE;
}

PyMethodDef methods[] = {
    {"element_wire", element_wire, METH_O,
     "element_wire(element) -> bytes | None: the element as wm_element_t encodes, or None when Python must "
     "encode it (skillbus.skill.tick_wire)."},
    {"params_wire", params_wire, METH_O,
     "params_wire(params) -> bytes: the skill_param_t's of a list of Params, as tick_wire.param_bytes writes "
     "them."},
    {"set_param_wire", set_param_wire, METH_VARARGS,
     "set_param_wire(type_names, Element, param_bytes, python_element_bytes): what params_wire reads types by "
     "and falls back to."},
    {nullptr, nullptr, 0, nullptr}};

}  // namespace

bool add_tick_wire(PyObject* module) {
  const std::pair<PyObject**, const char*> all[] = {
      {&names.key, "_key"},         {&names.values, "_values"},           {&names.defaults, "_default"},
      {&names.data_type, "_type"},  {&names.type, "type"},                {&names.description, "description"},
      {&names.param_type, "_param_type"}, {&names.options, "options"}};
  for (const auto& [slot, text] : all) {
    *slot = PyUnicode_InternFromString(text);
    if (!*slot) return false;
  }
  return PyModule_AddFunctions(module, methods) == 0;
}

}  // namespace skillbus::native
