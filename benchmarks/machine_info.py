"""What the benchmarks print about the machine they ran on."""
import os
import platform


def machine() -> str:
    """CPU model, core count, load average, OS and Python version, one line."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"{cpu}, {os.cpu_count()} cores (load average {load:.1f}), {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}")
