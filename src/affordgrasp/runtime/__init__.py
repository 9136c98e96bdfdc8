"""Process machinery: where the stages' work runs, how its processes live and end, how files land.

The stages call this package; it knows none of them (:mod:`affordgrasp.kernels`, which runs
the pipeline once to make every compiled kernel ready, sits above the stages it warms up).

* :mod:`.engines`: jobs run in this process, in local worker processes or on Ray, and
  the process pool other stages use;
* :mod:`.worker_lifetime`: worker processes end with their parent, ``kill -9`` included;
* :mod:`.process_tuning`: the allocator and BLAS threads of the processes affordgrasp owns;
* :mod:`.interrupts`: SIGTERM and SIGHUP handled as Ctrl-C;
* :mod:`.kernel_cache`: numba's on-disk caches of the kernels, valid and shippable;
* :mod:`.writing`: output paths checked up front, every file written atomically.

Nothing outside this package starts a process or replaces a file.
"""
