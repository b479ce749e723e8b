"""The engine of the sweeps: every evaluation is a task on Dask distributed.

``npstereo explore`` and ``npstereo report --paper`` hand their evaluations (a synthesis,
a quality measurement) to :func:`run_tasks`. By default they run on an embedded
``LocalCluster`` of this machine (one single-threaded worker process per core, loopback
only); ``--scheduler tcp://host:8786`` sends them to a user's running cluster instead,
with no other change. What Dask gives and the commands rely on:

- a worker process that dies (killed, out of memory, its machine lost) takes its tasks
  with it; the scheduler gives them to another worker, up to
  ``distributed.scheduler.allowed-failures`` deaths per task (:data:`ALLOWED_FAILURES` on
  the embedded cluster; a user's scheduler has its own setting), after which the task is
  reported failed (``KilledWorker``) and the sweep goes on;
- a task that raises is tried again :data:`RETRIES` times (``retries=`` of
  ``Client.submit``) before it counts as failed;
- tasks carry deterministic keys, so the same evaluation submitted twice (two clients of
  one cluster) is computed once;
- a run is submitted as one graph whose tasks carry their priority as an annotation: the
  scheduler then starts them in the caller's order (submitted one by one, the first few of
  each kind would go straight to the workers and run ahead of the rest);
- data many tasks need (a scene's images) is one task of the graph (:func:`shared`),
  sent once, and computed again from the graph if the worker holding it dies.

Results are cached by the callers in a file cache that the workers share
(:mod:`npstereo.gen.reports.cache`): a task that finds its result there returns it at once, and the
client does not submit what it finds there itself.
"""

import contextlib
import hashlib
import json
import logging
import os
import sys
from dataclasses import dataclass

from ...params import UserError

__all__ = ["CONNECT_TIMEOUT", "ALLOWED_FAILURES", "RETRIES", "Task", "TaskFailure",
           "task_key", "shared", "cluster", "run_tasks", "check_engine_arguments"]

# dask and distributed are imported in the functions that use them: together they take a
# second to import, and ``npstereo report`` of one configuration (which imports this
# module with the command) never starts a cluster.

#: Seconds to reach a user's scheduler before giving up with a one-line error.
CONNECT_TIMEOUT = 5
#: Seconds a user's scheduler may take to show at least one worker.
WORKER_TIMEOUT = 10
#: Worker deaths a task survives on the embedded cluster (Dask's default, made explicit).
ALLOWED_FAILURES = 3
#: Retries of a task that raised.
RETRIES = 2
#: Priority of the values tasks share (:func:`shared`), above any task's.
_FIRST = 2**31
#: Seconds between refreshes of the progress bar's running count.
_POLL = 1.0


@dataclass(frozen=True)
class Task:
    """One evaluation: ``function(*args)`` under the Dask key ``key``; ``label`` names it
    in progress lines. An argument made by :func:`shared` reaches ``function`` as the
    value it holds."""

    key: str
    function: object
    args: tuple
    label: str


@dataclass(frozen=True)
class TaskFailure:
    """A task that raised after its retries or killed too many workers."""

    message: str


def task_key(kind, *parts):
    """A deterministic Dask key: ``kind`` and a digest of ``parts`` (JSON-able)."""
    text = json.dumps(parts, sort_keys=True, default=repr)
    return f"{kind}-{hashlib.sha256(text.encode()).hexdigest()[:20]}"


def shared(value, key):
    """``value`` as one task of a run's graph under ``key``, for :class:`Task` arguments:
    tasks that all take it then share one copy instead of carrying one each.

    It is given the highest priority, so that the tasks waiting for it are not held back
    behind the rest of the run.
    """
    import dask
    with dask.annotate(priority=_FIRST):
        return dask.delayed(value, name=key, pure=True)


def check_engine_arguments(workers, scheduler):
    """One-line errors for ``--workers`` and ``--scheduler`` before any work is done."""
    if workers is not None and workers < 1:
        raise UserError(f"--workers must be an integer >= 1, not {workers}")
    if workers is not None and scheduler is not None:
        raise UserError("--workers sizes the embedded cluster: drop it with --scheduler "
                        "(the cluster there has its own workers)")


@contextlib.contextmanager
def cluster(scheduler=None, workers=None):
    """A connected ``distributed.Client``: to ``scheduler`` when given, else to an
    embedded ``LocalCluster`` of ``workers`` processes (default: one per core) on the
    loopback interface, closed on exit.

    Raises a one-line :class:`UserError` when ``scheduler`` does not answer within
    :data:`CONNECT_TIMEOUT` seconds or shows no worker within :data:`WORKER_TIMEOUT`.
    """
    import dask
    from distributed import Client, LocalCluster
    check_engine_arguments(workers, scheduler)
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError) as error:
            raise UserError(f"--scheduler {scheduler}: no Dask scheduler answered within "
                            f"{CONNECT_TIMEOUT} s ({type(error).__name__})") from None
        except (ValueError, TypeError) as error:
            raise UserError(f"--scheduler must be an address like tcp://host:8786, not "
                            f"{scheduler!r} ({error})") from None
        with contextlib.closing(client):
            try:
                client.wait_for_workers(1, timeout=WORKER_TIMEOUT)
            except TimeoutError:
                raise UserError(f"--scheduler {scheduler}: the scheduler has no worker "
                                f"(none joined within {WORKER_TIMEOUT} s)") from None
            yield client
        return
    count = workers or os.cpu_count() or 1
    with dask.config.set({"distributed.scheduler.allowed-failures": ALLOWED_FAILURES}):
        local = LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                             host="127.0.0.1", dashboard_address=None,
                             # The tools' memory is in their own processes; a limit on
                             # the worker would only restart it in the middle of a run.
                             memory_limit=0, silence_logs=logging.CRITICAL,
                             # The scheduler's HTTP routes (health, metrics) listen even
                             # without a dashboard, by default on 8787: a port of their
                             # own keeps two runs from colliding (and warning about it).
                             scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
    with local, Client(local) as client:
        yield client


def _executing(dask_worker):
    """On a worker: the keys of the tasks its threads are executing now."""
    return [ts.key for ts in dask_worker.state.executing]


def _running(client, keys):
    """How many of ``keys`` are executing on a worker (not merely queued there)."""
    try:
        answers = client.run(_executing, on_error="ignore")
    except (OSError, TimeoutError):  # a worker going away while asked
        return 0
    return sum(key in keys for executing in answers.values() for key in executing)


def _describe(error):
    return f"{type(error).__name__}: {error}".splitlines()[0][:300]


def run_tasks(client, tasks, desc, on_result=None):
    """Run ``tasks`` (in the order given: earlier ones start first) on ``client``'s cluster.

    A progress bar on stderr shows tasks done, running and failed. ``on_result(task,
    result, write)`` is called as each one finishes (``result`` a :class:`TaskFailure` for
    a failed task), ``write`` printing a line above the bar.

    Returns
    -------
    dict
        Task key -> result or :class:`TaskFailure`.
    """
    import dask
    from distributed import wait
    from tqdm import tqdm
    tasks = list(tasks)
    if len({t.key for t in tasks}) != len(tasks):
        raise ValueError("task keys must be unique")
    results = {}
    if not tasks:
        return results
    graph = []
    for i, t in enumerate(tasks):
        with dask.annotate(priority=len(tasks) - i):
            graph.append(dask.delayed(t.function, pure=True)(*t.args, dask_key_name=t.key))
    futures = dict(zip(client.compute(graph, retries=RETRIES), tasks))
    keys = {t.key for t in tasks}
    failed = 0
    with tqdm(total=len(tasks), desc=desc, unit="task", file=sys.stderr) as bar:
        pending = set(futures)
        while pending:
            try:
                done, pending = wait(pending, timeout=_POLL, return_when="FIRST_COMPLETED")
            except TimeoutError:
                done = set()
            for future in done:
                task = futures.pop(future)
                if future.status == "finished":
                    result = future.result()
                else:
                    # "error" carries the exception; "cancelled" (the scheduler lost
                    # the client or the task) carries none.
                    error = future.exception() if future.status == "error" else None
                    result = TaskFailure(_describe(error) if error is not None
                                         else f"task {future.status}")
                    failed += 1
                future.release()
                results[task.key] = result
                if on_result is not None:
                    on_result(task, result, lambda line: bar.write(line, file=sys.stderr))
                bar.update()
            status = f"running {_running(client, keys) if pending else 0}, failed {failed}"
            if status != bar.postfix:  # a redraw only on change keeps logs short
                bar.set_postfix_str(status)
    return results
