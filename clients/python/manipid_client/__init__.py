"""manipid_client — Python client of the manipid identification service (standard library only).

    from manipid_client import Client, local_server
    with local_server() as url:
        client = Client(url)
        ds = client.upload_dataset("run.csv")
        job = client.identify(ds, preset="cedro2009")
        print(job.wait(progress=True)["estimates"])

Client talks to a server; Job follows one job; local_server() runs a private server;
errors are ManipidError (problem+json fields) and its subclasses.
"""
from .client import Client, Dataset, History, Job
from .errors import (BinaryNotFound, JobCancelled, JobError, JobFailed, JobTimeout, ManipidConnectionError,
                     ManipidError, ServerStartError)
from .server import ServerURL, find_binary, local_server

__version__ = "0.1.0"

__all__ = [
    "Client", "Dataset", "History", "Job", "local_server", "find_binary", "ServerURL",
    "ManipidError", "ManipidConnectionError", "JobError", "JobFailed", "JobCancelled", "JobTimeout",
    "BinaryNotFound", "ServerStartError", "__version__",
]
