"""A finished run written into Blender: its image and passes, and its figures in WindowManager.caustic for the panels."""

from .images import write_image, write_passes

RESULT_IMAGE = "Caustic Render"


def record_run(props, job) -> None:
    """Show the finished `job`'s time and light rays in WindowManager.caustic `props`."""
    props.last_seconds = job.seconds
    props.last_lamp_rays = job.result.stats["lamp_rays"]
    props.last_refined = job.result.stats["lamp_rays_refined"]


def write_result(props, job):
    """The job's image and passes into "Caustic Render" and its passes (the
    add-on's own: writeback.images.own_image), its figures into `props`.
    Returns the image, whose name is the one to report."""
    image = write_image(RESULT_IMAGE, job.result.image)
    write_passes(RESULT_IMAGE, job.result.passes)
    record_run(props, job)
    return image
