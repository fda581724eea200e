"""Numba's on-disk cache, safe for processes that compile at the same moment.

Why: numba keeps the compiled variants of a cached function (one per signature and CPU) in
numbered data files, ``name.1.nbc``, ``name.2.nbc``, ..., listed in one index file. To save
a new variant it reads the index, takes the first number not listed, writes the index, then
the data. Two processes compiling *different* variants of one function at once (two pytest
workers, the processes of a Dask cluster, ``msens run`` beside its background compile) can
both take number k: the index then files one variant under k while the data file holds the
other's machine code, and every later process that loads the first variant runs the second
one's code (``tests/test_numba_cache_file.py`` forces that interleaving).

How: :class:`KeyedCacheFile` names each data file by a digest of what identifies its
content (the function's source stamp and the variant's index key: signature, CPU, bytecode),
and writes the data before the index. A data file therefore only ever holds the variant its
name stands for, whoever wrote it last, and an index entry never names a file that is not
yet written. What the race can still do is drop an index entry that another process wrote
at the same moment: the variant is then compiled once more, never loaded wrong.

Where: :func:`install` makes numba create a :class:`KeyedCacheFile` for every cached
function defined after it in this process (numba picks the class by a module-level name
when ``@njit(cache=True)`` runs); every msens module that defines cached numba functions
imports this one first. Functions of other packages in the same process get the same,
safer files; their cache stays readable by numba's own class (an index maps variants to
file names, whatever the names are).
"""

from __future__ import annotations

import hashlib

from msens.numba_cache import use_user_cache

use_user_cache()  # before numba reads its configuration

from numba.core import caching  # noqa: E402

#: numba's own class, kept for :func:`install` and the tests.
NUMBA_CACHE_FILE = caching.IndexDataCacheFile


class KeyedCacheFile(NUMBA_CACHE_FILE):
    """numba's index-and-data cache file with one data file per variant, named by its key.

    Parameters are numba's: the cache folder, the base of the file names and the source
    stamp of the function (its file's modification time and size, or the chain kernel's
    content digest, :mod:`msens.chain.kernel.cache_guard`).
    """

    def data_name(self, key) -> str:
        """The data file's name for a variant: ``<base>.<16 hex digits>.nbc``.

        The digest covers numba's version, the source stamp and the index key (the
        variant's signature, the CPU it was compiled for, the hashes of the function's
        bytecode and closure), by their text: the same in every process.
        """
        text = repr((self._version, self._source_stamp, key)).encode()
        return self._data_name_pattern.replace(
            "{number:d}", hashlib.sha256(text).hexdigest()[:16])

    def save(self, key, data) -> None:
        """Write the variant's data file, then list it in the index (if not yet listed)."""
        name = self.data_name(key)
        self._save_data(name, data)
        overloads = self._load_index()
        if overloads.get(key) != name:
            overloads[key] = name
            self._save_index(overloads)

    def load(self, key):
        """The variant's data, or None if the index does not list it under its keyed name
        (an entry that numba's own class numbered is compiled afresh, never trusted)."""
        name = self.data_name(key)
        if self._load_index().get(key) != name:
            return None
        try:
            return self._load_data(name)
        except OSError:  # removed since the index was read
            return None


def install() -> None:
    """Make numba create a :class:`KeyedCacheFile` for each cached function defined from
    now on (idempotent)."""
    caching.IndexDataCacheFile = KeyedCacheFile


install()
