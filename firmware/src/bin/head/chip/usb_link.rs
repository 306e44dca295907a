//! The USB link: a CDC-ACM port carrying COBS frames (postcard-rpc's serial
//! framing). Two tasks move packets between the endpoints and two bounded
//! channels of whole frames; the core sees only [`UsbLink`].
//!
//! Why CDC-ACM rather than postcard-rpc's raw bulk interface: the simulated
//! head is reached on a pseudo-terminal with the same framing, so `gonio scan
//! --port PATH` drives both through one code path, and the head needs no
//! driver on any operating system.

use core::sync::atomic::{AtomicU32, Ordering};
use embassy_executor::Spawner;
use embassy_futures::select::{select, Either};
use embassy_stm32::peripherals::{PA11, PA12, USB_OTG_FS};
use embassy_stm32::usb::Driver;
use embassy_stm32::Peri;
use embassy_sync::blocking_mutex::raw::ThreadModeRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use embassy_usb::class::cdc_acm::{CdcAcmClass, ControlChanged, Receiver, Sender, State};
use embassy_usb::{Builder, UsbDevice};
use gonio_firmware::link::{Link, LinkError};
use gonio_shared::identity::{USB_PID, USB_VID};
use gonio_shared::wire::framing::{self, Decoder, MAX_ENCODED, MAX_FRAME};
use static_cell::StaticCell;

type UsbDriver = Driver<'static, USB_OTG_FS>;
type Frame = heapless::Vec<u8, MAX_FRAME>;

const PACKET: u16 = 64;
/// Frames one packet can end: the shortest (a header of a 1-byte key and
/// sequence number, no body, the 4-byte check, COBS's code byte and
/// delimiter) takes 9 bytes, so 64 end at most 8 (the first begun in the
/// packet before).
const FRAMES_PER_PACKET: usize = 8;
/// How long a frame may wait for room in the transmit queue (ms): eight
/// frames ahead of it at 64 bytes a millisecond take far less.
const SEND_TIMEOUT_MS: u64 = 500;

/// The queues and signals are shared by thread-mode tasks only (the core's
/// and the two USB tasks; the OTG interrupt only wakes them), so their
/// mutex is the thread-mode one: a critical section around a 256-byte
/// frame's copy held the step timer's interrupt off for 330 cycles on the
/// virtual board (`board-bench`'s `interrupt_worst_wait`), a STEP edge
/// 2.9 ticks late.
static RX: Channel<ThreadModeRawMutex, Frame, 4> = Channel::new();
static TX: Channel<ThreadModeRawMutex, Frame, 8> = Channel::new();
/// Sessions started since boot: each start and each end is signalled with
/// the session's number, so that an end nobody was serving (a bus reset or
/// suspend while the head waited between sessions) cannot end the next
/// one: it would meet that session's first request, and the head would
/// not answer again until the next re-plug.
static SESSION: AtomicU32 = AtomicU32::new(0);
static DISCONNECTED: Signal<ThreadModeRawMutex, u32> = Signal::new();
static CONNECTED: Signal<ThreadModeRawMutex, u32> = Signal::new();

fn start_session() {
    CONNECTED.signal(SESSION.fetch_add(1, Ordering::Relaxed).wrapping_add(1));
}

fn end_session() {
    DISCONNECTED.signal(SESSION.load(Ordering::Relaxed));
}

/// The core's end of the USB link: the session it serves (0 before the
/// first).
pub struct UsbLink {
    session: u32,
}

impl UsbLink {
    pub async fn wait_connection(&mut self) {
        self.session = CONNECTED.wait().await;
    }

    /// Whether a signalled end concerns this session (or a later one), not
    /// one that ended before it started.
    fn ends_this(&self, ended: u32) -> bool {
        ended.wrapping_sub(self.session) < u32::MAX / 2
    }
}

fn copy(f: Frame, buf: &mut [u8]) -> usize {
    let n = f.len().min(buf.len());
    buf[..n].copy_from_slice(&f[..n]);
    n
}

impl Link for UsbLink {
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        loop {
            match select(RX.receive(), DISCONNECTED.wait()).await {
                Either::First(f) => return Ok(copy(f, buf)),
                Either::Second(ended) if self.ends_this(ended) => return Err(LinkError::Closed),
                Either::Second(_) => {}
            }
        }
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>> {
        if let Some(ended) = DISCONNECTED.try_take() {
            if self.ends_this(ended) {
                return Some(Err(LinkError::Closed));
            }
        }
        RX.try_receive().ok().map(|f| Ok(copy(f, buf)))
    }

    /// A host that stops reading (its port closed while the device stays
    /// configured: `write_packet` never completes and the queue fills) is a
    /// host gone: after [`SEND_TIMEOUT_MS`] the link counts as closed and the
    /// serve loop makes the head safe, instead of waiting in this send for
    /// ever with the laser on.
    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let f = Frame::from_slice(frame).map_err(|_| LinkError::Closed)?;
        match select(TX.send(f), Timer::after_millis(SEND_TIMEOUT_MS)).await {
            Either::First(()) => Ok(()),
            Either::Second(()) => Err(LinkError::Closed),
        }
    }
}

/// Bus events that end a session: a bus reset, a suspend (the host slept or
/// the cable is half out), losing the configuration; the host closing the
/// port is seen by `rx_task` (DTR). The core sees the link close, in the
/// middle of a move too, and stops.
struct BusWatch;

impl embassy_usb::Handler for BusWatch {
    fn reset(&mut self) {
        end_session();
    }

    /// A suspend ends the session (the head goes safe); a resume without a
    /// bus reset (the host woke, the device still configured and its port
    /// still open) starts the next one: nothing else would, `rx_task` never
    /// having left its session, and the head would stay silent until
    /// replugged. What was queued belongs to the session that ended.
    fn suspended(&mut self, suspended: bool) {
        if suspended {
            end_session();
        } else {
            RX.clear();
            TX.clear();
            start_session();
        }
    }

    fn configured(&mut self, configured: bool) {
        if !configured {
            end_session();
        }
    }

    /// VBUS gone (the cable pulled): the core's session-end interrupt,
    /// with no bus reset or suspend after it, since the pull-up on D+ goes
    /// with VBUS.
    fn enabled(&mut self, enabled: bool) {
        if !enabled {
            end_session();
        }
    }
}

#[embassy_executor::task]
async fn usb_device(mut dev: UsbDevice<'static, UsbDriver>) -> ! {
    dev.run().await
}

/// A session is a configured interface with the host's port open: DTR is
/// raised when a program opens the port (every CDC-ACM driver does) and
/// dropped when it closes it, the device staying configured. Closing the port
/// ends the session like a pulled cable.
#[embassy_executor::task]
async fn rx_task(mut rx: Receiver<'static, UsbDriver>, control: ControlChanged<'static>) -> ! {
    let mut dec = Decoder::new();
    let mut pkt = [0u8; PACKET as usize];
    loop {
        rx.wait_connection().await;
        while !rx.dtr() {
            control.control_changed().await;
        }
        // What is queued belongs to the session that ended. A disconnect the
        // core has not seen yet stays signalled: it ends its serve loop, and
        // only that one (`UsbLink::ends_this`).
        RX.clear();
        TX.clear();
        start_session();
        'session: loop {
            match select(rx.read_packet(&mut pkt), control.control_changed()).await {
                Either::First(Ok(n)) => {
                    let mut frames = heapless::Vec::<Frame, FRAMES_PER_PACKET>::new();
                    dec.feed(&pkt[..n], |f| {
                        if let Ok(f) = Frame::from_slice(f) {
                            let _ = frames.push(f);
                        }
                    });
                    // A full queue holds the reader back: the endpoint NAKs
                    // the host's next packets until the core has taken a
                    // frame, and nothing is dropped.
                    for f in frames {
                        loop {
                            match select(RX.send(f.clone()), control.control_changed()).await {
                                Either::First(()) => break,
                                Either::Second(()) if !rx.dtr() => break 'session,
                                Either::Second(()) => {}
                            }
                        }
                    }
                }
                Either::First(Err(_)) => break,
                Either::Second(()) if !rx.dtr() => break,
                Either::Second(()) => {}
            }
        }
        dec = Decoder::new();
        end_session();
    }
}

#[embassy_executor::task]
async fn tx_task(mut tx: Sender<'static, UsbDriver>) -> ! {
    let mut enc = [0u8; MAX_ENCODED];
    loop {
        let f = TX.receive().await;
        let Some(n) = framing::encode(&f, &mut enc) else { continue };
        // Frames go out in full packets; a frame ending on a packet boundary
        // is closed by a zero-length packet. With no host, frames are dropped.
        let mut ok = true;
        for chunk in enc[..n].chunks(PACKET as usize) {
            ok &= tx.write_packet(chunk).await.is_ok();
        }
        if ok && n % PACKET as usize == 0 {
            let _ = tx.write_packet(&[]).await;
        }
    }
}

/// Builds the USB device and starts its tasks.
pub fn start(spawner: &Spawner, usb: Peri<'static, USB_OTG_FS>, dp: Peri<'static, PA12>, dm: Peri<'static, PA11>) -> UsbLink {
    static EP_OUT: StaticCell<[u8; 256]> = StaticCell::new();
    static CONFIG_DESC: StaticCell<[u8; 256]> = StaticCell::new();
    static BOS_DESC: StaticCell<[u8; 256]> = StaticCell::new();
    static CONTROL: StaticCell<[u8; 64]> = StaticCell::new();
    static STATE: StaticCell<State> = StaticCell::new();
    static BUS_WATCH: StaticCell<BusWatch> = StaticCell::new();

    // The head has its own supply: with VBUS sensed on PA9, the core
    // connects the pull-up on D+ only while a host powers the bus (USB 2.0
    // §7.1.5.1: no pull-up current while VBUS is off), and says when the
    // cable goes.
    let mut cfg = embassy_stm32::usb::Config::default();
    cfg.vbus_detection = true;
    let driver = Driver::new_fs(usb, super::Irqs, dp, dm, EP_OUT.init([0; 256]), cfg);

    let mut dev_cfg = embassy_usb::Config::new(USB_VID, USB_PID);
    dev_cfg.manufacturer = Some("gonio");
    dev_cfg.product = Some("Retroreflection BRDF head");
    dev_cfg.serial_number = Some(embassy_stm32::uid::uid_hex());
    // The head runs from its own supply: from the bus it draws only the
    // VBUS sense divider's 0.34 mA (pins.rs) and the D+ pull-up's current.
    dev_cfg.self_powered = true;
    dev_cfg.max_power = 2;
    dev_cfg.max_packet_size_0 = 64;

    let mut builder = Builder::new(
        driver,
        dev_cfg,
        CONFIG_DESC.init([0; 256]),
        BOS_DESC.init([0; 256]),
        &mut [],
        CONTROL.init([0; 64]),
    );
    builder.handler(BUS_WATCH.init(BusWatch));
    let class = CdcAcmClass::new(&mut builder, STATE.init(State::new()), PACKET);
    let (tx, rx, control) = class.split_with_control();
    spawner.must_spawn(usb_device(builder.build()));
    spawner.must_spawn(rx_task(rx, control));
    spawner.must_spawn(tx_task(tx));
    UsbLink { session: 0 }
}
