#include "io/colmap_database.h"

#include <sqlite3.h>

#include "base/error.h"

namespace mvtm {

namespace {
const char* kSchema = R"SQL(
CREATE TABLE IF NOT EXISTS cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, prior_focal_length INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL, prior_qw REAL, prior_qx REAL, prior_qy REAL, prior_qz REAL, prior_tx REAL, prior_ty REAL, prior_tz REAL, CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647), FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));
CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name);
CREATE TABLE IF NOT EXISTS keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB);
CREATE TABLE IF NOT EXISTS two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);
)SQL";

struct Stmt {
  sqlite3_stmt* s = nullptr;
  Stmt(sqlite3* db, const char* sql, const std::string& path) {
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) != SQLITE_OK)
      throw Error(path, 0, std::string("database: ") + sqlite3_errmsg(db));
  }
  ~Stmt() { sqlite3_finalize(s); }
};
}  // namespace

ColmapDatabase::ColmapDatabase(const std::string& path) : path_(path) {
  if (sqlite3_open(path.c_str(), &db_) != SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error(path, 0, "cannot open database: " + msg);
  }
  try {
    Exec(kSchema);
  } catch (const Error&) {
    // Not a database (or a corrupt one): the destructor will not run, so close here.
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

ColmapDatabase::~ColmapDatabase() { sqlite3_close(db_); }

void ColmapDatabase::Exec(const std::string& sql) const {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw Error(path_, 0, "database: " + msg);
  }
}

void ColmapDatabase::Begin() { Exec("BEGIN TRANSACTION;"); }
void ColmapDatabase::Commit() { Exec("COMMIT;"); }

std::map<std::string, std::pair<uint32_t, uint32_t>> ColmapDatabase::Images() const {
  std::map<std::string, std::pair<uint32_t, uint32_t>> out;
  Stmt st(db_, "SELECT image_id, name, camera_id FROM images;", path_);
  while (sqlite3_step(st.s) == SQLITE_ROW) {
    const unsigned char* n = sqlite3_column_text(st.s, 1);
    out[n ? reinterpret_cast<const char*>(n) : ""] = {
        static_cast<uint32_t>(sqlite3_column_int64(st.s, 0)),
        static_cast<uint32_t>(sqlite3_column_int64(st.s, 2))};
  }
  return out;
}

namespace {
// Parameters 1..4 of a camera row: model, width, height, params (COLMAP's blob of doubles).
void BindCamera(sqlite3_stmt* s, const Camera& c) {
  sqlite3_bind_int64(s, 1, static_cast<int>(c.model));
  sqlite3_bind_int64(s, 2, static_cast<sqlite3_int64>(c.width));
  sqlite3_bind_int64(s, 3, static_cast<sqlite3_int64>(c.height));
  sqlite3_bind_blob(s, 4, c.params.data(), static_cast<int>(c.params.size() * sizeof(double)),
                    SQLITE_TRANSIENT);
}
}  // namespace

uint32_t ColmapDatabase::AddCamera(const Camera& c) {
  Stmt st(
      db_,
      "INSERT INTO cameras(model, width, height, params, prior_focal_length) VALUES(?,?,?,?,1);",
      path_);
  BindCamera(st.s, c);
  if (sqlite3_step(st.s) != SQLITE_DONE)
    throw Error(path_, 0, std::string("database: ") + sqlite3_errmsg(db_));
  return static_cast<uint32_t>(sqlite3_last_insert_rowid(db_));
}

void ColmapDatabase::UpdateCamera(uint32_t id, const Camera& c) {
  Stmt st(db_,
          "UPDATE cameras SET model=?, width=?, height=?, params=?, prior_focal_length=1 WHERE "
          "camera_id=?;",
          path_);
  BindCamera(st.s, c);
  sqlite3_bind_int64(st.s, 5, id);
  if (sqlite3_step(st.s) != SQLITE_DONE)
    throw Error(path_, 0, std::string("database: ") + sqlite3_errmsg(db_));
}

uint32_t ColmapDatabase::UpsertImage(const std::string& name, uint32_t wanted_id,
                                     uint32_t camera_id, const std::optional<Rigid3d>& prior) {
  if (!cache_loaded_) {
    cache_ = Images();
    cache_loaded_ = true;
  }
  auto it = cache_.find(name);
  // The prior's seven values (NULL without one) bound from the statement's column `first`.
  const auto bind_prior = [&prior](sqlite3_stmt* s, int first) {
    if (!prior) {
      for (int i = 0; i < 7; ++i) sqlite3_bind_null(s, first + i);
      return;
    }
    const auto& q = prior->q;
    const auto& t = prior->t;
    const double v[7] = {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()};
    for (int i = 0; i < 7; ++i) sqlite3_bind_double(s, first + i, v[i]);
  };
  if (it != cache_.end()) {
    Stmt st(db_,
            "UPDATE images SET camera_id=?, prior_qw=?, prior_qx=?, prior_qy=?, prior_qz=?, "
            "prior_tx=?, prior_ty=?, prior_tz=? WHERE image_id=?;",
            path_);
    sqlite3_bind_int64(st.s, 1, camera_id);
    bind_prior(st.s, 2);
    sqlite3_bind_int64(st.s, 9, it->second.first);
    if (sqlite3_step(st.s) != SQLITE_DONE)
      throw Error(path_, 0, std::string("database: ") + sqlite3_errmsg(db_));
    return it->second.first;
  }
  Stmt st(db_,
          "INSERT INTO images(image_id, name, camera_id, prior_qw, prior_qx, prior_qy, prior_qz, "
          "prior_tx, prior_ty, prior_tz) VALUES(?,?,?,?,?,?,?,?,?,?);",
          path_);
  sqlite3_bind_int64(st.s, 1, wanted_id);
  sqlite3_bind_text(st.s, 2, name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int64(st.s, 3, camera_id);
  bind_prior(st.s, 4);
  if (sqlite3_step(st.s) != SQLITE_DONE)
    throw Error(path_, 0, "database: image " + name + ": " + sqlite3_errmsg(db_));
  cache_[name] = {wanted_id, camera_id};
  return wanted_id;
}

}  // namespace mvtm
