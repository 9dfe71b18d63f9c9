"""A run's progress callback (c0_run_conf_set_progress) in Python: calls the
user's fn(stage, fraction), or draws a tqdm bar (progress=True; a plain
line on stderr where tqdm is not installed). An exception raised inside fn,
or a Ctrl-C that arrives during the run (Python raises it inside the
callback, the first Python code that runs), asks the library to stop; the
caller re-raises it unchanged once the run has returned.

Ctrl-C: a KeyboardInterrupt raised on entry to a ctypes callback cannot be
caught there (ctypes prints and drops it), so while the run works on the
main thread its SIGINT handler only notes the signal; the callback then asks
the run to stop, and the previous handler gets the signal once the run has
returned (Python's default raises KeyboardInterrupt)."""
import ctypes
import signal
import sys
import threading

CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_char_p, ctypes.c_double, ctypes.c_void_p)


class _Bar:
    """One tqdm bar per stage (percent), or a line on stderr without tqdm."""

    def __init__(self):
        try:
            from tqdm import tqdm
        except ImportError:
            tqdm = None
        self.tqdm, self.bar, self.stage = tqdm, None, None

    def __call__(self, stage, fraction):
        if stage != self.stage:
            self.close()
            self.stage = stage
            if self.tqdm:
                self.bar = self.tqdm(total=100, desc=stage, unit="%", leave=True,
                                     bar_format="{desc:<10} {percentage:3.0f}%|{bar}| {elapsed}")
        if self.bar is not None:
            self.bar.update(round(100 * fraction) - self.bar.n)
        else:
            sys.stderr.write("\r%-10s %3.0f%%" % (stage, 100 * fraction) + ("\n" if fraction >= 1 else ""))
            sys.stderr.flush()

    def close(self):
        if self.bar is not None:
            self.bar.close()
            self.bar = None


class Observer:
    """The C callback of one run; error holds what fn (or Ctrl-C) raised."""

    def __init__(self, progress):
        if progress is True:
            progress = _Bar()
        elif progress is not None and progress is not False and not callable(progress):
            raise TypeError("progress: expected a callable fn(stage, fraction), True or None, got %s"
                            % type(progress).__name__)
        self.fn = progress or None
        self.error = None
        self.sigint = None         # the frame a SIGINT arrived in, during the run
        self.prev = None
        self.c = CALLBACK(self._call)   # kept alive as long as the run

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self.prev = signal.signal(signal.SIGINT, self._on_sigint)
        return self

    def _on_sigint(self, sig, frame):
        self.sigint = (sig, frame)

    def __exit__(self, *exc):
        if self.prev is not None:
            signal.signal(signal.SIGINT, self.prev)
        if isinstance(self.fn, _Bar):
            self.fn.close()
        if self.sigint is not None and self.error is None and callable(self.prev):
            self.prev(*self.sigint)   # the default handler raises KeyboardInterrupt
        return False

    def _call(self, stage, fraction, user):
        if self.error is not None or self.sigint is not None:
            return 1
        try:
            if self.fn is not None:
                self.fn(stage.decode(), fraction)
            return 0
        except BaseException as e:   # KeyboardInterrupt and SystemExit too: raised again unchanged
            self.error = e
            return 1
