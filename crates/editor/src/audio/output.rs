//! The sound device: the default output of the system's default host (ALSA on Linux, through
//! `cpal`), opened on a thread of its own that owns the stream (a `cpal::Stream` may not leave
//! the thread that made it, and a device that is slow to open holds up no frame). Its callback
//! renders the shared [`Transport`].

use std::sync::mpsc;
use std::sync::{Arc, Mutex};

use cpal::traits::{DeviceTrait, HostTrait, StreamTrait};

use super::transport::Transport;

/// An open output stream; dropping it stops the stream and ends its thread.
pub struct Output {
    pub transport: Arc<Mutex<Transport>>,
    /// Dropped to end the stream's thread.
    _stop: mpsc::Sender<()>,
}

/// Why no sound output could be opened.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot start the sound thread: {0}")]
    Thread(std::io::Error),
    #[error("the system reports none")]
    NoDevice,
    #[error("{0}")]
    Config(#[from] cpal::DefaultStreamConfigError),
    #[error("the output device takes {0:?} samples, which keyrig does not write")]
    SampleFormat(cpal::SampleFormat),
    #[error("{0}")]
    Build(#[from] cpal::BuildStreamError),
    #[error("the output device does not start: {0}")]
    Play(#[from] cpal::PlayStreamError),
}

/// What opening the device gave: the stream, or why there is none.
pub type Opened = Result<Output, OutputError>;

/// Starts opening the default output device on a thread; the answer comes on the receiver.
#[must_use]
pub fn open() -> mpsc::Receiver<Opened> {
    let (answer, receive) = mpsc::channel();
    let spawned = std::thread::Builder::new().name("keyrig-audio".into()).spawn({
        let answer = answer.clone();
        move || {
            let (stop, stopped) = mpsc::channel::<()>();
            match start_stream() {
                Ok((stream, transport)) => {
                    if answer.send(Ok(Output { transport, _stop: stop })).is_ok() {
                        // Holds the stream until the editor drops the Output (or exits).
                        let _ = stopped.recv();
                    }
                    drop(stream);
                }
                Err(e) => {
                    let _ = answer.send(Err(e));
                }
            }
        }
    });
    if let Err(e) = spawned {
        let _ = answer.send(Err(OutputError::Thread(e)));
    }
    receive
}

/// Opens the default output and starts its stream (rendering silence until told to play).
fn start_stream() -> Result<(cpal::Stream, Arc<Mutex<Transport>>), OutputError> {
    quiet_alsa_on_this_thread();
    let host = cpal::default_host();
    let device = host.default_output_device().ok_or(OutputError::NoDevice)?;
    let supported = device.default_output_config()?;
    let format = supported.sample_format();
    let config: cpal::StreamConfig = supported.into();
    let transport = Arc::new(Mutex::new(Transport::new(config.sample_rate.0, config.channels)));
    let stream = match format {
        cpal::SampleFormat::F32 => build::<f32>(&device, &config, &transport),
        cpal::SampleFormat::I16 => build::<i16>(&device, &config, &transport),
        cpal::SampleFormat::U16 => build::<u16>(&device, &config, &transport),
        cpal::SampleFormat::I32 => build::<i32>(&device, &config, &transport),
        other => return Err(OutputError::SampleFormat(other)),
    }?;
    stream.play()?;
    Ok((stream, transport))
}

fn build<T: cpal::SizedSample + cpal::FromSample<f32>>(
    device: &cpal::Device,
    config: &cpal::StreamConfig,
    transport: &Arc<Mutex<Transport>>,
) -> Result<cpal::Stream, OutputError> {
    let transport = Arc::clone(transport);
    let mut mixed: Vec<f32> = Vec::new();
    device
        .build_output_stream(
            config,
            move |data: &mut [T], _: &cpal::OutputCallbackInfo| {
                mixed.resize(data.len(), 0.0);
                match transport.lock() {
                    Ok(mut t) => t.render(&mut mixed),
                    Err(_) => mixed.fill(0.0),
                }
                for (out, &s) in data.iter_mut().zip(&mixed) {
                    *out = <T as cpal::Sample>::from_sample(s);
                }
            },
            // A stream error (the device unplugged) leaves the sound silent; the editor goes on.
            |_| {},
            None,
        )
        .map_err(OutputError::from)
}

/// ALSA prints every failure of the device's configuration to stderr itself, besides
/// returning it: eight lines where there is no sound card (CI, Xvfb). The failure reaches the
/// editor as cpal's error and the status bar says it once, so the thread that opens the device
/// gives ALSA an error handler of its own that drops the messages (`snd_lib_error_set_local`,
/// a handler for the calling thread only, alsa-lib 1.1.6 and later; other threads' ALSA
/// messages, and everything else on stderr, are untouched).
#[cfg(target_os = "linux")]
fn quiet_alsa_on_this_thread() {
    use std::os::raw::{c_char, c_int};
    unsafe extern "C" fn drop_message(
        _file: *const c_char,
        _line: c_int,
        _function: *const c_char,
        _err: c_int,
        _fmt: *const c_char,
        _args: *mut alsa_sys::__va_list_tag,
    ) {
    }
    // SAFETY: alsa-lib stores the pointer in a thread-local and calls it with the declared
    // arguments, which `drop_message` never reads; the function lives as long as the program.
    unsafe {
        alsa_sys::snd_lib_error_set_local(Some(drop_message));
    }
}

#[cfg(not(target_os = "linux"))]
fn quiet_alsa_on_this_thread() {}
