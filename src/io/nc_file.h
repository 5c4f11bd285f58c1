// Internal to the io module: a checked netCDF file (UGRID net files, Exodus II).
#pragma once

#include <netcdf.h>

#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "polysquare/core/error.h"

namespace polysquare {

// One open netCDF file; every call is checked, the file is closed on every path.
class NcFile {
 public:
  /// mode: NC_64BIT_OFFSET (classic, 64-bit offset) by default; NC_NETCDF4 | NC_CLASSIC_MODEL etc. as given.
  NcFile(const std::filesystem::path& tmp, std::string name, int mode = NC_64BIT_OFFSET) : name_(std::move(name)) {
    check(nc_create(tmp.c_str(), NC_CLOBBER | mode, &id_), "create");
    open_ = true;
  }
  ~NcFile() {
    if (open_) nc_close(id_);
  }
  NcFile(const NcFile&) = delete;
  NcFile& operator=(const NcFile&) = delete;

  void check(int status, const std::string& what) const {
    if (status != NC_NOERR) throw InputError(name_ + ": netCDF " + what + ": " + nc_strerror(status));
  }
  int dim(const std::string& n, std::size_t len) {
    int d = 0;
    check(nc_def_dim(id_, n.c_str(), len, &d), "dimension " + n);
    return d;
  }
  int var(const std::string& n, nc_type type, std::vector<int> dims) {
    int v = 0;
    check(nc_def_var(id_, n.c_str(), type, static_cast<int>(dims.size()), dims.data(), &v), "variable " + n);
    return v;
  }
  void text(int v, const std::string& att, const std::string& value) {
    check(nc_put_att_text(id_, v, att.c_str(), value.size(), value.c_str()), "attribute " + att);
  }
  void texts(int v, std::initializer_list<std::pair<const char*, std::string>> atts) {
    for (const auto& [att, value] : atts) text(v, att, value);
  }
  void integer(int v, const std::string& att, int value) {
    check(nc_put_att_int(id_, v, att.c_str(), NC_INT, 1, &value), "attribute " + att);
  }
  void real(int v, const std::string& att, double value) {
    check(nc_put_att_double(id_, v, att.c_str(), NC_DOUBLE, 1, &value), "attribute " + att);
  }
  void end_definitions() { check(nc_enddef(id_), "enddef"); }
  void put(int v, const std::vector<double>& data) { check(nc_put_var_double(id_, v, data.data()), "write"); }
  void put(int v, const std::vector<int>& data) { check(nc_put_var_int(id_, v, data.data()), "write"); }
  void put(int v, const std::vector<char>& data) { check(nc_put_var_text(id_, v, data.data()), "write"); }
  void global_float(const std::string& att, float value) {
    check(nc_put_att_float(id_, NC_GLOBAL, att.c_str(), NC_FLOAT, 1, &value), "attribute " + att);
  }
  int id() const { return id_; }
  void close() {
    open_ = false;
    check(nc_close(id_), "close");
  }

 private:
  std::string name_;
  int id_ = -1;
  bool open_ = false;
};

}  // namespace polysquare
