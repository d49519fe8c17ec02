#pragma once
/// Reader of the LASA handwriting dataset (Khansari-Zadeh & Billard, IEEE T-RO 2011) as exported to
/// CSV in ../shared/data/lasa_handwriting (see its README.md): one file `csv/<Shape>.csv` per shape
/// with the header `demo,t,x,y,vx,vy,ax,ay` and consecutive rows per demonstration (demo 0, 1, ...;
/// 1000 rows each in the shipped copy), positions in tablet units ending at the goal (0, 0),
/// per-demo time stamps t (s) and the recorded velocities. The accelerations are read (checked)
/// but not kept. No resampling, smoothing or normalisation is applied here (see
/// datasets/demonstrations.h for Downsample, FitNormalisation, ApplyNormalisation).
///
/// The data directory resolves like every data file: ResolveDataFile(root, "lasa_handwriting")
/// (datasets/data_root.h).

#include <string>
#include <vector>

#include "datasets/demonstrations.h"

namespace foresight {

/// The shape names (file stems of <lasa_dir>/csv/*.csv), sorted. Error naming the directory when
/// it does not exist or holds no CSV file.
std::vector<std::string> ListLasaShapes(const std::string& lasa_dir);

/// Reads <lasa_dir>/csv/<shape>.csv into a 2-D DemoSet named `shape` (one Demonstration per demo
/// index). Errors name the file (and line): a missing file, a header other than
/// `demo,t,x,y,vx,vy,ax,ay`, a row without exactly 8 fields, a field that is not a number or not
/// finite, a demo index that is not an integer or does not continue the sequence 0, 1, 2, ...
/// (the same index or the next one), time that does not increase within a demo, no rows.
/// Demos of different lengths are accepted.
DemoSet ReadLasaShape(const std::string& lasa_dir, const std::string& shape);

}  // namespace foresight
