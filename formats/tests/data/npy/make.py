"""Writes the .npy fixtures of formats/tests/npy.rs with NumPy itself, so the
reader is tested against files NumPy wrote, not against our idea of them.

Run once (needs numpy; the crate and its tests do not):
    python3 formats/tests/data/npy/make.py
The matrices are the foods vectors of ../foods_vectors.tsv (water, carbs,
protein, fat per 100 g), whose rows follow ../foods.csv.
"""

import csv
import io
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(HERE, "..", "foods_vectors.tsv"), newline="") as f:
    rows = list(csv.reader(f, delimiter="\t"))[1:]
ids = [r[0] for r in rows]
m = np.array([[float(v) for v in r[1:]] for r in rows], dtype=np.float64)


def save(name, array, version=None):
    path = os.path.join(HERE, name)
    with open(path, "wb") as f:
        if version is None:
            np.save(f, array)
        else:
            np.lib.format.write_array(f, array, version=version)


# The table's row order, in every layout the reader must accept.
save("foods_f8.npy", m)                              # '<f8', C order, version 1.0
save("foods_f4.npy", m.astype("<f4"))                # '<f4'
save("foods_f8_be.npy", m.astype(">f8"))             # big endian
save("foods_f4_be.npy", m.astype(">f4"))
save("foods_fortran.npy", np.asfortranarray(m))      # fortran_order: True
save("foods_v2.npy", m, version=(2, 0))              # 4-byte header length
save("foods_v3.npy", m, version=(3, 0))              # UTF-8 header
# Rows in another order, with their ids beside them (one per line, after a
# header line).
order = [(7 * i) % 20 for i in range(20)]  # a permutation: 7 is prime to 20
save("foods_shuffled.npy", m[order])
with open(os.path.join(HERE, "foods_shuffled_ids.txt"), "w") as f:
    f.write("id\n" + "".join(ids[i] + "\n" for i in order))
# What the reader must refuse, each with a clear message.
save("foods_i8.npy", m.astype("<i8"))                # integers
save("foods_f2.npy", m.astype("<f2"))                # float16
save("foods_1d.npy", m[:, 0].copy())                 # not a matrix
save("foods_3d.npy", m.reshape(20, 2, 2))            # not a matrix
save("foods_19rows.npy", m[:19])                     # a row short
save("foods_record.npy", np.zeros(3, dtype=[("x", "<f8"), ("y", "<f8")]))
with_nan = m.copy()
with_nan[4, 2] = np.nan                              # row 5 (strawberry), column 3
save("foods_nan.npy", with_nan)
