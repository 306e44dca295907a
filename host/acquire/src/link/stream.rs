//! COBS frames over a serial port: the real head's USB CDC-ACM port or the
//! simulated head's pseudo-terminal.

use super::{config, WireClosed, Workers};
use anyhow::{Context, Result};
use gonio_shared::wire::framing::{self, Decoder};
use postcard_rpc::host_client::{HostClient, WireRx, WireTx};
use postcard_rpc::standard_icd::WireError;
use std::collections::VecDeque;
use tokio::io::{AsyncReadExt, AsyncWriteExt, ReadHalf, WriteHalf};
use tokio_serial::{SerialPortBuilderExt, SerialStream};

struct Tx(WriteHalf<SerialStream>);

struct Rx {
    port: ReadHalf<SerialStream>,
    decoder: Decoder,
    frames: VecDeque<Vec<u8>>,
}

impl WireTx for Tx {
    type Error = WireClosed;
    async fn send(&mut self, data: Vec<u8>) -> Result<(), WireClosed> {
        let data = super::seal(data);
        let mut out = vec![0u8; data.len() + data.len() / 254 + 2];
        let n = framing::encode(&data, &mut out).ok_or_else(|| WireClosed("frame too long".into()))?;
        self.0.write_all(&out[..n]).await.map_err(|e| WireClosed(e.to_string()))?;
        self.0.flush().await.map_err(|e| WireClosed(e.to_string()))
    }
}

impl WireRx for Rx {
    type Error = WireClosed;
    async fn receive(&mut self) -> Result<Vec<u8>, WireClosed> {
        let mut buf = [0u8; 1024];
        loop {
            if let Some(f) = self.frames.pop_front().and_then(super::open) {
                return Ok(f);
            }
            if !self.frames.is_empty() {
                continue;
            }
            let n = self.port.read(&mut buf).await.map_err(|e| WireClosed(e.to_string()))?;
            if n == 0 {
                return Err(WireClosed("port closed".into()));
            }
            let frames = &mut self.frames;
            self.decoder.feed(&buf[..n], |f| frames.push_back(f.to_vec()));
        }
    }
}

/// Opens a head's serial port (baud rate is irrelevant on USB CDC-ACM and
/// on a pseudo-terminal). Must be called within a tokio runtime.
pub fn serial_client(path: &str) -> Result<(HostClient<WireError>, Workers)> {
    let mut port = tokio_serial::new(path, 115_200)
        .open_native_async()
        .with_context(|| format!("cannot open the head's port {path}"))?;
    // The head serves a session while DTR is up (closing the port drops it).
    // Most drivers raise it on open; some (Windows without flow control) do
    // not. A pseudo-terminal has no modem lines: the error is ignored there.
    let _ = tokio_serial::SerialPort::write_data_terminal_ready(&mut port, true);
    let (rx, tx) = tokio::io::split(port);
    let rx = Rx {
        port: rx,
        decoder: Decoder::new(),
        frames: VecDeque::new(),
    };
    let workers = Workers::default();
    let client = HostClient::new_with_wire_and_config(Tx(tx), rx, workers.clone(), &config());
    Ok((client, workers))
}
