//! scanline3d on real hardware: a Raspberry Pi Pico (RP2040) renders a spinning cube into an
//! ST7789 240×240 SPI panel, one row at a time, with no frame buffer anywhere. Each finished
//! row goes straight from the renderer's row buffer to the panel's memory window.
//!
//! # Wiring (the pin-out of the Waveshare Pico-LCD-1.3; any ST7789 240×240 module works)
//!
//! | panel | Pico pin | RP2040 function |
//! |-------|----------|-----------------|
//! | SCK   | GP10     | SPI1 SCK        |
//! | MOSI  | GP11     | SPI1 TX         |
//! | CS    | GP9      | GPIO output     |
//! | DC    | GP8      | GPIO output     |
//! | RST   | GP12     | GPIO output     |
//! | BL    | GP13     | GPIO output (backlight on) |
//! | VCC / GND | 3V3(OUT) / GND | |
//!
//! # Build, flash, run
//!
//! Building needs no board and no rustflags (`build.rs` passes the linker script):
//!
//! ```sh
//! cd examples/panel-rp2040
//! cargo build --release --target thumbv6m-none-eabi
//! ```
//!
//! Running needs the hardware. Hold BOOTSEL while plugging the Pico in, then
//! `cargo run --release --target thumbv6m-none-eabi` flashes it with `elf2uf2-rs -d`
//! (`cargo install elf2uf2-rs`; see `.cargo/config.toml`), or with a debug probe:
//! `probe-rs run --chip RP2040 target/thumbv6m-none-eabi/release/scanline3d-panel-rp2040`.
//! A setup fault halts the core (`panic-halt`): attach a debugger to see where.
#![no_std]
#![no_main]
// No unsafe code here: the one exception, marked below, is where the boot loader must sit.
#![deny(unsafe_code)]

use core::convert::Infallible;

use embedded_graphics::pixelcolor::Rgb565;
use embedded_hal::digital::OutputPin;
use embedded_hal::spi::MODE_0;
use embedded_hal_bus::spi::ExclusiveDevice;
use mipidsi::interface::SpiInterface;
use mipidsi::models::ST7789;
use mipidsi::options::ColorInversion;
use panic_halt as _;
use rp2040_hal::{self as hal, fugit::RateExtU32, gpio::FunctionSpi, pac, Clock};
use scanline3d::scene::{Instance, Light, Scene, Transform};
use scanline3d::sink::{FnSink, Row};
use scanline3d::{Config, Flat, Settings, Storage};
use static_cell::ConstStaticCell;

/// The second-stage boot loader for the Pico's W25Q080 flash, placed in the first 256 bytes of
/// flash by `memory.x`. (`link_section` counts as unsafe code: the linker places it.)
#[allow(unsafe_code)]
#[link_section = ".boot2"]
#[used]
pub static BOOT2_FIRMWARE: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The Pico's crystal.
const XTAL_HZ: u32 = 12_000_000;
/// Panel size.
const W: usize = 240;
const H: usize = 240;
/// SPI clock: the RP2040's maximum at a 125 MHz peripheral clock. Halve it if long wires
/// garble the picture.
const SPI_HZ: u32 = 62_500_000;

// The scene: a cube (shared with the window example).
#[path = "../../shared/cube.rs"]
mod cube;
use cube::CUBE;

const BACKGROUND: Rgb565 = Rgb565::new(3, 7, 6);

// ---- The renderer's memory. ----

/// Every precision choice: RGB565 rows, flat shading, the library's reference precision.
type Cfg = Settings<Rgb565, Flat>;
/// Room for all 12 triangles (even with culling off) and every one crossing a row.
type Ws = Storage<Cfg, W, H, 12, 12>;

/// The renderer's memory, in a static, initialised by the `const fn Storage::new` at compile
/// time.
///
/// Why `ConstStaticCell`: its value is a constant placed in `.data` by the linker and copied to
/// RAM by the reset handler, so it is never built on the stack (it costs its size in flash for
/// the initial image instead). `cortex_m::singleton!` builds the value in a local first, and
/// `StaticCell::init_with` builds it at run time in place only if the optimiser elides the
/// closure's return copy (no guarantee). A `critical_section::Mutex<RefCell<_>>` would be
/// const-initialised too, but every frame would render with interrupts off. `take` hands out
/// the one `&'static mut`.
static WORKSPACE: ConstStaticCell<Ws> = ConstStaticCell::new(Ws::new(BACKGROUND));

/// What can go wrong while setting up. A real firmware would log it (defmt, RTT); here the
/// core halts in the panic handler, where a debugger shows which one.
#[derive(Debug)]
enum Fault {
    Clocks,
    Pin,
    Display,
    Scene,
    Workspace,
    Render,
}

// `hal::entry` wraps cortex-m-rt's entry and first releases the RP2040's hardware spinlocks,
// which a debugger reset can leave held (the critical section uses one).
#[hal::entry]
fn main() -> ! {
    match run() {
        Ok(never) => match never {},
        Err(fault) => panic!("{:?}", fault),
    }
}

fn run() -> Result<Infallible, Fault> {
    let mut pac = pac::Peripherals::take().ok_or(Fault::Clocks)?;
    let mut watchdog = hal::Watchdog::new(pac.WATCHDOG);
    let clocks = hal::clocks::init_clocks_and_plls(
        XTAL_HZ,
        pac.XOSC,
        pac.CLOCKS,
        pac.PLL_SYS,
        pac.PLL_USB,
        &mut pac.RESETS,
        &mut watchdog,
    )
    .map_err(|_| Fault::Clocks)?;
    // The 1 MHz timer: delays for the panel's reset and chip select, and the animation clock.
    let mut timer = hal::Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);

    let sio = hal::Sio::new(pac.SIO);
    let pins = hal::gpio::Pins::new(
        pac.IO_BANK0,
        pac.PADS_BANK0,
        sio.gpio_bank0,
        &mut pac.RESETS,
    );
    let sck = pins.gpio10.into_function::<FunctionSpi>();
    let mosi = pins.gpio11.into_function::<FunctionSpi>();
    let cs = pins.gpio9.into_push_pull_output();
    let dc = pins.gpio8.into_push_pull_output();
    let rst = pins.gpio12.into_push_pull_output();
    let mut backlight = pins.gpio13.into_push_pull_output();

    // Write-only bus (the panel is never read), 8-bit frames.
    let bus = hal::Spi::<_, _, _, 8>::new(pac.SPI1, (mosi, sck)).init(
        &mut pac.RESETS,
        clocks.peripheral_clock.freq(),
        SPI_HZ.Hz(),
        MODE_0,
    );
    let spi = ExclusiveDevice::new(bus, cs, timer).map_err(|_| Fault::Pin)?;

    // mipidsi batches pixels through this buffer: one 240-pixel row of RGB565 is 480 bytes, so
    // each row leaves in a single SPI write.
    let mut spi_buffer = [0u8; W * 2];
    let interface = SpiInterface::new(spi, dc, &mut spi_buffer);
    let mut display = mipidsi::Builder::new(ST7789, interface)
        .display_size(W as u16, H as u16)
        // Most 240×240 ST7789 modules (the Waveshare one included) need inverted colours.
        .invert_colors(ColorInversion::Inverted)
        .reset_pin(rst)
        .init(&mut timer)
        .map_err(|_| Fault::Display)?;
    backlight.set_high().map_err(|_| Fault::Pin)?;

    let ws = WORKSPACE.try_take().ok_or(Fault::Workspace)?;
    let camera = Cfg::camera([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.5, 20.0)
        .map_err(|_| Fault::Scene)?;
    let light = Light::new([-0.4, 0.7, 0.6], 0.25, 0.75).map_err(|_| Fault::Scene)?;

    loop {
        // The pose follows the clock, not the frame count, so the spin speed does not depend
        // on the frame rate. The 24 s loop keeps the f32 angles small (and exact) forever.
        let t = (timer.get_counter().ticks() / 1000 % 24_000) as f32 / 24_000.0;
        let turn = core::f32::consts::TAU * t;
        let spin = Transform::rotation_y(3.0 * turn).then_after(&Transform::rotation_x(2.0 * turn));
        let instances = [Instance {
            mesh: &CUBE,
            transform: spin,
        }];
        let scene = Scene::new(&instances, camera, light).map_err(|_| Fault::Scene)?;

        // Each finished row goes straight into a one-row window of the panel's memory.
        let mut panel = FnSink(|row: Row<'_, Rgb565>| {
            display.set_pixels(0, row.y, W as u16 - 1, row.y, row.pixels.iter().copied())
        });
        // With this scene and workspace no error can occur (capacities fit, the transform
        // stays in the envelope, and the RP2040's SPI and pins cannot fail): treat one as a
        // fault.
        ws.render(&scene, &mut panel).map_err(|_| Fault::Render)?;
    }
}
