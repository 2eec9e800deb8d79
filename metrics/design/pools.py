"""Where chunks of a search run: local processes (``process_pool``) or a Dask cluster.

``run_study`` submits ``search_chunk`` calls to a ``LocalPool`` or a ``DaskPool`` and takes
results as they finish; an interrupt stops the processes a pool owns (``stop_process_pool``).
"""
from __future__ import annotations

import contextlib
import os
import signal
import threading
from concurrent.futures import ProcessPoolExecutor


def process_pool(workers: int):
    """A ``ProcessPoolExecutor`` for ``run_study(executor=...)``: spawn start method (no fork of
    a parent that may hold threads, e.g. a Qt app or a dask client).

    Parameters
    ----------
    workers : int
        Worker processes.

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        Its workers ignore SIGINT (the parent stops them, ``stop_process_pool``).
    """
    import multiprocessing
    return _QuietSpawnPool(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                           initializer=_worker_ignores_sigint)


class _QuietSpawnPool(ProcessPoolExecutor):
    """A pool whose workers cannot be interrupted before their initializer, nor the parent
    half-way through starting them.

    Workers are started inside ``submit`` (all of them at the first, for the spawn method). A
    spawned worker unpickles (imports numpy, metrics, ...) before its initializer runs; a Ctrl-C
    to the process group in that window printed a KeyboardInterrupt traceback from the child.
    And a Ctrl-C or SIGTERM raised in the parent between a child's start and the write of its
    start-up data left a child printing ``EOFError: Ran out of input`` that the pool did not yet
    list. So, for the call (main thread only), both signals are held (``_signals_held``).
    """

    def submit(self, *args, **kwargs):
        if threading.current_thread() is not threading.main_thread():
            return super().submit(*args, **kwargs)
        with _signals_held():
            return super().submit(*args, **kwargs)


_HELD = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def _signals_held():
    """Hold SIGINT and SIGTERM that arrive inside the block; deliver them on leaving.

    The parent's Python handlers only record them meanwhile (the CLI's raise: Ctrl-C as
    ``KeyboardInterrupt``, SIGTERM as ``app.cli.Terminated``), and SIGINT is blocked in this
    thread's signal mask, which a spawned child inherits through exec: a Ctrl-C reaching a
    starting worker stays pending until its initializer ignores SIGINT and unblocks it
    (``_worker_ignores_sigint``), and is then dropped. (Ignoring SIGINT in the parent instead,
    whose disposition a child would inherit too, lost a Ctrl-C pressed during the call.) Python
    handlers do not survive exec: the workers keep SIGTERM's default action for
    ``stop_process_pool``.
    """
    held: list[int] = []
    previous = {s: signal.signal(s, lambda signum, frame: held.append(signum)) for s in _HELD}
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})     # a pending Ctrl-C acts now
        for s in dict.fromkeys(held):
            os.kill(os.getpid(), s)                                     # to the restored handler


def _worker_ignores_sigint() -> None:
    """In a pool's worker: Ctrl-C (sent by a terminal to the whole process group) is the parent's
    to handle; it stops the workers (``stop_process_pool``) instead of each printing a traceback.
    The worker started with SIGINT blocked (``_signals_held``): once ignored, a pending one is
    dropped as it is unblocked."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def stop_process_pool(executor) -> None:
    """Stop a ``process_pool`` now: queued chunks cancelled, running worker processes terminated.

    For an interrupt (Ctrl-C, SIGTERM, MemoryError): ``shutdown(wait=True)`` would wait for every
    running chunk to finish.

    Parameters
    ----------
    executor : concurrent.futures.ProcessPoolExecutor
        A pool from ``process_pool``.

    Returns
    -------
    None
    """
    procs = list((getattr(executor, "_processes", None) or {}).values())
    executor.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=2.0)


class SharedFile:
    """An object pickled once to a temporary file; it pickles as its path and unpickles as the
    object, loaded once per process (``_SHARED`` keeps the last one by key).

    ``LocalPool.share`` makes one per study and deletes the file when the pool closes.
    """

    def __init__(self, obj) -> None:
        import os
        import pickle
        import tempfile
        import uuid
        self.key = uuid.uuid4().hex
        fd, self.path = tempfile.mkstemp(prefix="isoforce-study-", suffix=".pickle")
        try:
            with os.fdopen(fd, "wb") as fh:
                pickle.dump(obj, fh, protocol=pickle.HIGHEST_PROTOCOL)
        except BaseException:
            self.remove()
            raise
        _SHARED.clear()
        _SHARED[self.key] = obj              # this process has it already

    def __reduce__(self):
        return _load_shared, (self.path, self.key)

    def remove(self) -> None:
        """Delete the file (the workers that loaded it keep their copy).

        Returns
        -------
        None
        """
        import contextlib
        import os
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.path)


_SHARED: dict[str, object] = {}


def _load_shared(path: str, key: str):
    """The object of a ``SharedFile``: from this process's cache, else read from ``path``."""
    obj = _SHARED.get(key)
    if obj is None:
        import pickle
        with open(path, "rb") as fh:
            obj = pickle.load(fh)
        _SHARED.clear()                      # one study at a time: keep memory bounded
        _SHARED[key] = obj
    return obj


class LocalPool:
    """Chunks on a concurrent.futures executor; closed at the end only if ``run_study`` made it.

    ``share`` (what every task takes), ``submit``, ``wait_first`` (the futures done first),
    ``close``, ``abort``: what the runner asks of a pool (``DaskPool`` answers the same for a Dask cluster).
    """

    def __init__(self, workers: int, executor=None) -> None:
        self.owned = executor is None
        self.pool = process_pool(workers) if executor is None else executor
        self.shared: list[SharedFile] = []

    def share(self, obj):
        """``obj`` pickled once to a file; the tasks carry its path (``SharedFile``).

        A process pool pickles every task's arguments: a paper-scale study (2.4 million
        samples, 97 MB) would be pickled and piped once per chunk, hundreds of times.

        Parameters
        ----------
        obj : object
            What every task needs (the study).

        Returns
        -------
        SharedFile
            Unpickles as ``obj`` in a worker, read from the file once per process.
        """
        ref = SharedFile(obj)
        self.shared.append(ref)
        return ref

    def _forget(self) -> None:
        for ref in self.shared:
            ref.remove()
        self.shared.clear()

    def submit(self, fn, *args, **kwargs):
        """Run ``fn(*args, **kwargs)`` on the executor.

        Parameters
        ----------
        fn : callable
            A picklable function (``search_chunk``).
        *args, **kwargs
            Its arguments.

        Returns
        -------
        concurrent.futures.Future
        """
        return self.pool.submit(fn, *args, **kwargs)

    @staticmethod
    def wait_first(futures):
        """Block until at least one of ``futures`` is done.

        Parameters
        ----------
        futures : iterable of concurrent.futures.Future
            Futures from ``submit``.

        Returns
        -------
        set of concurrent.futures.Future
            The ones done.
        """
        from concurrent.futures import FIRST_COMPLETED, wait
        done, _ = wait(futures, return_when=FIRST_COMPLETED)
        return done

    def close(self) -> None:
        """Shut an owned executor down after its chunks (a caller's executor is left open).

        Returns
        -------
        None
        """
        if self.owned:
            self.pool.shutdown(wait=True, cancel_futures=True)
        self._forget()

    def abort(self) -> None:
        """Interrupted: stop an owned pool's processes at once (a caller's pool is the caller's).

        Returns
        -------
        None
        """
        if self.owned:
            stop_process_pool(self.pool)
            self.owned = False
        self._forget()


class DaskPool:
    """Chunks on a ``dask.distributed`` client's cluster (the cluster's workers are not ours to stop)."""

    def __init__(self, client) -> None:
        self.client = client

    def share(self, obj):
        """``obj`` sent to every worker once (``Client.scatter(broadcast=True)``), as a future the
        tasks take in its place: a paper-scale study carries 2.4 million samples (97 MB), which
        would otherwise travel with each of its hundreds of chunks.

        Parameters
        ----------
        obj : object
            What every task needs (the study).

        Returns
        -------
        distributed.Future
        """
        return self.client.scatter(obj, broadcast=True, hash=False)

    def submit(self, fn, *args, **kwargs):
        """Run ``fn(*args, **kwargs)`` on the cluster (``pure=False``: never deduplicated).

        Parameters
        ----------
        fn : callable
            A picklable function (``search_chunk``).
        *args, **kwargs
            Its arguments.

        Returns
        -------
        distributed.Future
        """
        return self.client.submit(fn, *args, pure=False, **kwargs)

    @staticmethod
    def wait_first(futures):
        """Block until at least one of ``futures`` is done.

        Parameters
        ----------
        futures : iterable of distributed.Future
            Futures from ``submit``.

        Returns
        -------
        set of distributed.Future
            The ones done.
        """
        from distributed import wait
        done, _ = wait(list(futures), return_when="FIRST_COMPLETED")
        return done

    def close(self) -> None:
        """Nothing to do: the client and its cluster are the caller's.

        Returns
        -------
        None
        """
        pass

    def abort(self) -> None:
        """Nothing to do: the cluster's workers are not ours to stop.

        Returns
        -------
        None
        """
        pass


def dask_threads(client) -> int:
    """Total worker threads of a dask client's cluster.

    Parameters
    ----------
    client : distributed.Client
        A connected client.

    Returns
    -------
    int
        At least 1.
    """
    info = client.scheduler_info()
    workers = info.get("workers", {}) if isinstance(info, dict) else {}
    return max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))
