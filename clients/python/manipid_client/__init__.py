"""manipid_client — Python client of the manipid identification service (standard library only).

    from manipid_client import Client, local_server
    with local_server() as url:
        client = Client(url)
        ds = client.upload_dataset("run.csv")
        job = client.identify(ds, preset="cedro2009")
        print(job.wait(progress=True)["estimates"])

Your own arm (a URDF robot):

    arm = client.upload_robot("arm.urdf")
    job = client.identify(client.upload_dataset("run.csv"), robot=arm, validate=check)
    result = job.robot_result()          # base_parameters, friction, point by name
    client.to_urdf(job, "arm-identified.urdf")

Client talks to a server; Job follows one job; Dataset and Robot are stored resources;
RobotResult reads a robot identification's result by name; local_server() runs a private
server; errors are ManipidError (problem+json fields) and its subclasses.
"""
from .client import Client, Dataset, History, Job, Robot
from .errors import (BinaryNotFound, JobCancelled, JobError, JobFailed, JobTimeout, ManipidConnectionError,
                     ManipidError, ServerStartError)
from .results import Estimate, RobotResult, base_value
from .server import ServerURL, find_binary, local_server

__version__ = "0.1.0"

__all__ = [
    "Client", "Dataset", "History", "Job", "Robot", "RobotResult", "Estimate", "base_value",
    "local_server", "find_binary", "ServerURL",
    "ManipidError", "ManipidConnectionError", "JobError", "JobFailed", "JobCancelled", "JobTimeout",
    "BinaryNotFound", "ServerStartError", "__version__",
]
