//! `rtk render`: a scene through the render loop into an image or a film
//! file. Everything the render path owns lives here: the loop and its f64
//! film, the film file of checkpoints and crops, and the services the host
//! gives integrators and shaders.

pub(crate) mod film_file;
pub(crate) mod render_loop;
pub(crate) mod tracer;
