// skillbus_native.attach_channel_filter(fd, channels) -> str and detach_channel_filter(fd):
// the kernel filter of
// skillbus/channel_filter.hpp on a Python bus's udpm:// socket (skillbus.udpm). "" when
// attached, else why not (the socket then takes every datagram, as without a filter).
#include "glue.hpp"
#include "skillbus/channel_filter.hpp"

namespace skillbus::native {

namespace {

PyObject* attach(PyObject*, PyObject* args) {
  int fd = -1;
  PyObject* list = nullptr;
  if (!PyArg_ParseTuple(args, "iO", &fd, &list)) return nullptr;
  PyObject* seq = PySequence_Fast(list, "attach_channel_filter: channels must be a sequence of str");
  if (!seq) return nullptr;
  std::vector<std::string> channels;
  const Py_ssize_t n = PySequence_Fast_GET_SIZE(seq);
  for (Py_ssize_t i = 0; i < n; ++i) {
    std::string c;
    if (!utf8_of(PySequence_Fast_GET_ITEM(seq, i), c, "attach_channel_filter: a channel")) {
      Py_DECREF(seq);
      return nullptr;
    }
    channels.push_back(std::move(c));
  }
  Py_DECREF(seq);
  std::string why;
  if (attach_channel_filter(fd, channels, why)) why.clear();
  return PyUnicode_FromStringAndSize(why.data(), static_cast<Py_ssize_t>(why.size()));
}

PyObject* detach(PyObject*, PyObject* args) {
  int fd = -1;
  if (!PyArg_ParseTuple(args, "i", &fd)) return nullptr;
  detach_channel_filter(fd);
  Py_RETURN_NONE;
}

PyMethodDef methods[] = {
    {"attach_channel_filter", attach, METH_VARARGS,
     "attach_channel_filter(fd, channels) -> str: drop LCM messages of other channels in the kernel; "
     "'' when attached, else why not."},
    {"detach_channel_filter", detach, METH_VARARGS,
     "detach_channel_filter(fd): the socket takes every datagram again."},
    {nullptr, nullptr, 0, nullptr}};

}  // namespace

bool add_channel_filter(PyObject* module) { return PyModule_AddFunctions(module, methods) == 0; }

}  // namespace skillbus::native
