// skillbus_native.Sealer and .Opener: the CPython glue of skillbus/auth.hpp's, which
// skillbus.auth uses for the bus when the module is built (the same bytes and rules as its
// Python ones, at a fifth of their cost).
//
//   Sealer(key: bytes, identity: bytes).seal(channel: str, payload) -> bytes
//   Opener(keys: list[bytes], policy_text: str | None).open(channel: str, data)
//       -> (True, payload: bytes, identity: str, "") | (False, reason: str, identity: str, why: str)
#include <memory>
#include <string>
#include <vector>

#include "glue.hpp"
#include "shared_opener.hpp"
#include "skillbus/auth.hpp"

namespace skillbus::native {

namespace {

struct PySealer {
  PyObject_HEAD
  auth::Sealer* core;
};

struct PyOpener {
  PyObject_HEAD
  std::shared_ptr<SharedOpener>* core;  // (shared with the QuietFrames made with it)
};

int sealer_init(PyObject* self_obj, PyObject* args, PyObject*) {
  auto* self = reinterpret_cast<PySealer*>(self_obj);
  PyObject *key_obj, *identity_obj;
  if (!PyArg_ParseTuple(args, "SS", &key_obj, &identity_obj)) return -1;
  Bytes key, identity;
  if (!bytes_of(key_obj, key, "key") || !bytes_of(identity_obj, identity, "identity")) return -1;
  if (self->core) {
    PyErr_SetString(PyExc_RuntimeError, "a Sealer is initialised once");
    return -1;
  }
  try {
    self->core = new auth::Sealer(std::move(key), std::string(identity.begin(), identity.end()));
  } catch (const std::exception& e) {
    self->core = nullptr;
    PyErr_SetString(PyExc_ValueError, e.what());
    return -1;
  }
  return 0;
}

void sealer_dealloc(PyObject* self_obj) {
  delete reinterpret_cast<PySealer*>(self_obj)->core;
  Py_TYPE(self_obj)->tp_free(self_obj);
}

PyObject* sealer_seal(PyObject* self_obj, PyObject* args) {
  auto* core = reinterpret_cast<PySealer*>(self_obj)->core;
  const char* channel;
  Py_ssize_t channel_size;
  Py_buffer payload;
  if (!core) return PyErr_Format(PyExc_RuntimeError, "Sealer is not initialised");
  if (!PyArg_ParseTuple(args, "s#y*", &channel, &channel_size, &payload)) return nullptr;
  PyObject* out = nullptr;
  try {
    const Bytes sealed = core->seal(std::string(channel, size_t(channel_size)), payload.buf, size_t(payload.len));
    out = PyBytes_FromStringAndSize(reinterpret_cast<const char*>(sealed.data()), Py_ssize_t(sealed.size()));
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
  }
  PyBuffer_Release(&payload);
  return out;
}

PyObject* sealer_incarnation(PyObject* self_obj, void*) {
  auto* core = reinterpret_cast<PySealer*>(self_obj)->core;
  return core ? PyLong_FromUnsignedLongLong(core->incarnation()) : PyErr_Format(PyExc_RuntimeError, "not initialised");
}

int opener_init(PyObject* self_obj, PyObject* args, PyObject*) {
  auto* self = reinterpret_cast<PyOpener*>(self_obj);
  PyObject* keys_obj;
  PyObject* policy_obj;
  if (!PyArg_ParseTuple(args, "OO", &keys_obj, &policy_obj)) return -1;
  std::vector<auth::Key> keys;
  PyObject* it = PyObject_GetIter(keys_obj);
  if (!it) return -1;
  while (PyObject* k = PyIter_Next(it)) {
    Bytes key;
    const bool ok = bytes_of(k, key, "a key");
    Py_DECREF(k);
    if (!ok) {
      Py_DECREF(it);
      return -1;
    }
    keys.push_back(std::move(key));
  }
  Py_DECREF(it);
  if (PyErr_Occurred()) return -1;
  if (keys.empty()) {
    PyErr_SetString(PyExc_ValueError, "an Opener needs at least one key");
    return -1;
  }
  try {
    std::shared_ptr<const auth::Policy> policy;
    if (policy_obj != Py_None) {
      std::string text;
      if (!utf8_of(policy_obj, text, "policy_text")) return -1;
      policy = std::make_shared<auth::Policy>(auth::Policy::parse(text, "the bus policy"));
    }
    if (self->core) {
      PyErr_SetString(PyExc_RuntimeError, "an Opener is initialised once");
      return -1;
    }
    self->core = new std::shared_ptr<SharedOpener>(std::make_shared<SharedOpener>(std::move(keys), std::move(policy)));
  } catch (const std::exception& e) {
    self->core = nullptr;
    PyErr_SetString(PyExc_ValueError, e.what());
    return -1;
  }
  return 0;
}

void opener_dealloc(PyObject* self_obj) {
  delete reinterpret_cast<PyOpener*>(self_obj)->core;
  Py_TYPE(self_obj)->tp_free(self_obj);
}

PyObject* opener_open(PyObject* self_obj, PyObject* args) {
  auto* holder = reinterpret_cast<PyOpener*>(self_obj)->core;
  SharedOpener* core = holder ? holder->get() : nullptr;
  const char* channel;
  Py_ssize_t channel_size;
  Py_buffer data;
  if (!core) return PyErr_Format(PyExc_RuntimeError, "Opener is not initialised");
  if (!PyArg_ParseTuple(args, "s#y*", &channel, &channel_size, &data)) return nullptr;
  size_t payload_size = 0;
  std::string identity, why;
  auth::Reason reason{};
  PyObject* out = nullptr;
  try {
    const auto* bytes = static_cast<const uint8_t*>(data.buf);
    bool ok;
    {
      std::lock_guard<std::mutex> lock(core->mutex);
      ok = core->opener.open(std::string(channel, size_t(channel_size)), bytes, size_t(data.len), payload_size,
                             identity, reason, why);
    }
    if (ok)
      out = Py_BuildValue("(Oy#s#s)", Py_True, reinterpret_cast<const char*>(bytes), Py_ssize_t(payload_size), "", 0,
                          "");
    else
      out = Py_BuildValue("(Oss#s)", Py_False, auth::reason_name(reason), "", 0, "");
    if (out && !identity.empty()) {  // (utf-8 with replacement, as Python's Opener decodes it)
      PyObject* id = PyUnicode_DecodeUTF8(identity.data(), Py_ssize_t(identity.size()), "replace");
      if (!id || PyTuple_SetItem(out, 2, id) != 0) Py_CLEAR(out);
    }
    if (out && !ok && !why.empty()) {
      PyObject* w = PyUnicode_DecodeUTF8(why.data(), Py_ssize_t(why.size()), "replace");
      if (!w || PyTuple_SetItem(out, 3, w) != 0) Py_CLEAR(out);
    }
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
  }
  PyBuffer_Release(&data);
  return out;
}

PyMethodDef sealer_methods[] = {
    {"seal", sealer_seal, METH_VARARGS, "The payload with its trailer (skillbus.auth's format)."},
    {nullptr, nullptr, 0, nullptr}};
PyGetSetDef sealer_getset[] = {
    {"incarnation", sealer_incarnation, nullptr, "This sealer's incarnation (its start, ns).", nullptr},
    {nullptr, nullptr, nullptr, nullptr, nullptr}};
PyMethodDef opener_methods[] = {
    {"open", opener_open, METH_VARARGS, "(True, payload, identity, '') or (False, reason, identity, why)."},
    {nullptr, nullptr, 0, nullptr}};

PyTypeObject sealer_type = {PyVarObject_HEAD_INIT(nullptr, 0)};
PyTypeObject opener_type = {PyVarObject_HEAD_INIT(nullptr, 0)};

}  // namespace

std::shared_ptr<SharedOpener> opener_of(PyObject* o) {
  if (!PyObject_TypeCheck(o, &opener_type) || !reinterpret_cast<PyOpener*>(o)->core) return nullptr;
  return *reinterpret_cast<PyOpener*>(o)->core;
}

bool add_auth(PyObject* module) {
  sealer_type.tp_name = "skillbus_native.Sealer";
  sealer_type.tp_basicsize = sizeof(PySealer);
  sealer_type.tp_flags = Py_TPFLAGS_DEFAULT;
  sealer_type.tp_doc = "Appends the bus's trailer to what one process publishes (skillbus/auth.hpp).";
  sealer_type.tp_new = PyType_GenericNew;
  sealer_type.tp_init = sealer_init;
  sealer_type.tp_dealloc = sealer_dealloc;
  sealer_type.tp_methods = sealer_methods;
  sealer_type.tp_getset = sealer_getset;
  opener_type.tp_name = "skillbus_native.Opener";
  opener_type.tp_basicsize = sizeof(PyOpener);
  opener_type.tp_flags = Py_TPFLAGS_DEFAULT;
  opener_type.tp_doc = "Verifies and strips the bus's trailers; keeps the replay windows (skillbus/auth.hpp).";
  opener_type.tp_new = PyType_GenericNew;
  opener_type.tp_init = opener_init;
  opener_type.tp_dealloc = opener_dealloc;
  opener_type.tp_methods = opener_methods;
  return add_type(module, sealer_type, "Sealer") && add_type(module, opener_type, "Opener");
}

}  // namespace skillbus::native
